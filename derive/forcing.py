"""Split an external force f(t) into constant and harmonic parts, where it has that form.

``f(t) = A + Σ_h (B_h cos(Ω_h t) + C_h sin(Ω_h t))`` with A, B, C, Ω free of t
is what the exact linear solution can integrate in closed form (steady state
plus transient). Anything else (``exp(-t)``, ``cos(t**2)``, ``t*cos(t)``) is
reported as not harmonic, and only the integrators apply.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class Harmonic:
    """``cos_amp·cos(Ω t) + sin_amp·sin(Ω t)``."""

    omega: sp.Expr
    cos_amp: sp.Expr
    sin_amp: sp.Expr


def _linear_in_t(arg: sp.Expr, t: sp.Symbol) -> tuple[sp.Expr, sp.Expr] | None:
    poly = sp.Poly(sp.expand(arg), t) if arg.has(t) else None
    if poly is None or poly.degree() != 1:
        return None
    a, b = poly.all_coeffs()
    if a.has(t) or b.has(t):
        return None
    return a, b


def decompose(expr: sp.Expr, t: sp.Symbol) -> tuple[sp.Expr, list[Harmonic]] | None:
    """Constant part and harmonics of ``expr``, or None if it is not of that form.

    Harmonics with the same frequency are merged; frequencies are kept as
    expressions (their sign normalised so that Ω is written as given).
    """
    const = sp.Integer(0)
    by_freq: dict[sp.Expr, list[sp.Expr]] = {}
    for term in sp.Add.make_args(sp.expand(expr)):
        if not term.has(t):
            const += term
            continue
        coeff, rest = term.as_independent(t, as_Add=False)
        if not isinstance(rest, (sp.cos, sp.sin)):
            return None
        lin = _linear_in_t(rest.args[0], t)
        if lin is None:
            return None
        a, b = lin
        # cos(a t + b) = cos b cos(at) - sin b sin(at);  sin(a t + b) = sin b cos(at) + cos b sin(at)
        if isinstance(rest, sp.cos):
            cc, ss = coeff * sp.cos(b), -coeff * sp.sin(b)
        else:
            cc, ss = coeff * sp.sin(b), coeff * sp.cos(b)
        if a.could_extract_minus_sign():
            a, ss = -a, -ss
        amps = by_freq.setdefault(a, [sp.Integer(0), sp.Integer(0)])
        amps[0] += cc
        amps[1] += ss
    harmonics = [Harmonic(w, c, s) for w, (c, s) in sorted(by_freq.items(), key=lambda kv: sp.default_sort_key(kv[0]))]
    return const, harmonics


def constant_part(expr: sp.Expr, t: sp.Symbol) -> sp.Expr:
    """The constant part of ``expr`` (its mean over t): ``A`` of a constant + harmonic form (:func:`decompose`),
    else the terms free of t once the trigonometric functions are written as exponentials (``sin(t)**2`` has
    1/2, ``1 + exp(-t)`` has 1). A static load: it moves a potential scene's equilibrium as a constant force."""
    if not expr.has(t):
        return expr
    parts = decompose(expr, t)
    if parts is not None:
        return parts[0]
    const = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr.rewrite(sp.exp))):
        if not term.has(t):
            const += term
    return sp.simplify(const)


def harmonics_by_mass(forces, t: sp.Symbol):
    """Constant parts and harmonics of forces ``[(on, f(t)), ...]`` on single masses, or None if
    any force is not constant + harmonic.

    Returns ``(const, omegas, amplitudes)``: ``const`` maps a mass index to its constant force,
    ``omegas`` are the frequencies (sorted by SymPy's default key) and ``amplitudes`` holds one
    ``(cos_amp, sin_amp)`` pair of such maps per frequency. Zero terms are left out.
    """
    const: dict = {}
    table: dict = {}
    for on, f in forces:
        parts = decompose(f, t)
        if parts is None:
            return None
        c, harmonics = parts
        if c != 0:
            const[on] = const.get(on, 0) + c
        for h in harmonics:
            cos_amp, sin_amp = table.setdefault(h.omega, ({}, {}))
            if h.cos_amp != 0:
                cos_amp[on] = cos_amp.get(on, 0) + h.cos_amp
            if h.sin_amp != 0:
                sin_amp[on] = sin_amp.get(on, 0) + h.sin_amp
    omegas = sorted(table, key=sp.default_sort_key)
    return const, omegas, [table[w] for w in omegas]


def harmonic_table(forces, t: sp.Symbol, n: int):
    """:func:`harmonics_by_mass` as dense lists over ``n`` masses, or None.

    Returns ``(const, omegas, cos_amp, sin_amp)``: ``const`` a list of n expressions,
    ``cos_amp``/``sin_amp`` one such list per frequency.
    """
    parts = harmonics_by_mass(forces, t)
    if parts is None:
        return None
    const, omegas, amplitudes = parts

    def dense(by_mass: dict) -> list:
        return [by_mass.get(i, sp.Integer(0)) for i in range(n)]

    return dense(const), omegas, [dense(c) for c, _ in amplitudes], [dense(s) for _, s in amplitudes]
