"""Every deterministic work cap of the symbolic side, in one place (sizes, never a clock).

Whether a scene gets a closed form must not depend on how busy the machine is: ``springchain
derive`` writes the same module on any machine under any load (``derive --check`` is stable), and
``modes`` answers in seconds on any small scene. Each symbolic step therefore measures the size of
its input (or of its intermediate results, as it goes) against one of the limits below *before* the
expensive work, and past it takes the accurate numeric route at the scene's values (mpmath
eigensolvers settled to float64, exact rational solves, the spring-factor SVD), with a note; the
report's ``closed form:`` line says which parts stayed closed-form.

The modules keep their historical names for these limits (``work.MAX_DET_TERMS``,
``modes.MAX_ROOT_OPS``, ...) as aliases of the fields of :data:`CAPS`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Caps:
    """The limits (see each field's comment; "ops" is SymPy's ``count_ops``)."""

    #: Closed-form modes: largest block (after rigid-body modes and mirror symmetry) whose
    #: characteristic polynomial is expanded symbolically.
    symbolic_block: int = 6
    #: Closed-form modes and transfer functions: largest bound on the monomials of a determinant
    #: (:func:`work.det_terms_bound`, computed before expanding it). Bundled scenes: at most 36; a
    #: general 4-mass chain of 9 symbols: 400 (~1.5 s); a general 5-mass chain: 2000 (no readable form).
    det_terms: int = 1000
    #: Closed-form modes, ζ, Γ: most decimal digits of an exact number (float literals such as
    #: ``2e-70`` are exact rationals; factoring 600-digit determinants takes seconds).
    number_digits: int = 40
    #: Closed-form modes: largest root (ops) kept as a closed form.
    root_ops: int = 120
    #: Damping ratios: largest ``φᵀ C φ / φᵀ M φ`` (ops) simplified into a closed-form ζ.
    zeta_ops: int = 400
    #: Participation: largest ``Σ mᵢφᵢ`` plus ``Σ mᵢφᵢ²`` (ops) simplified into closed-form Γ and M*.
    participation_input_ops: int = 2000
    #: Participation: largest closed-form Γ or M* (ops) kept.
    participation_ops: int = 400
    #: Transfer functions: most masses of a ``[masses]`` scene given a closed-form H(s).
    transfer_masses: int = 6
    #: Static sag ``K⁻¹ M g``: most masses solved symbolically (past it: an exact rational solve
    #: at the scene's values).
    sag_masses: int = 8
    #: Static sag: most monomials (numerator plus denominator) of any entry during the symbolic
    #: elimination; the elimination stops at the first entry past it (6 hung masses of distinct
    #: names: at most 27; a dense 8-mass K of 30 symbols runs past it at once).
    sag_terms: int = 200
    #: Static sag: most characters of the longest closed-form entry that is factored and printed
    #: (longer ones are given as values, as a text report's closed forms).
    sag_chars: int = 160
    #: Potentials: largest gradient entry (ops) SymPy is asked to ``simplify`` to test x = 0 for an
    #: equilibrium (larger ones take the loading path, which finds x = 0 too).
    simplify_ops: int = 200
    #: Sensitivities: largest derivative (ops) kept as a closed form.
    sensitivity_ops: int = 400
    #: Sensitivities: largest derivative (ops) that is ``cancel``/``factor``-ed.
    sensitivity_simplify_ops: int = 60
    #: Sensitivities: largest shape component (ops) whose derivative is sought in closed form.
    sensitivity_shape_ops: int = 40
    #: Rayleigh targets (equal ζ): largest α = 2ζω_aω_b/(ω_a + ω_b) (ops, before simplifying) whose
    #: denominator SymPy's ``radsimp`` rationalises (3 masses with closed-form ω: 85-89; 2 general masses
    #: of 5 symbols: 257, 1.5 s).
    rayleigh_ops: int = 300
    #: Rayleigh targets (equal ζ): deepest nesting of radicals with symbols in ω_a + ω_b that ``radsimp``
    #: is asked to rationalise (ω = √ω² of a quadratic's root: 2; a spring k = "sqrt(k)" inside that root:
    #: 3, where each squaring multiplies sums of nested radicals: > 80 s on 3 masses of 5 generic floats).
    rayleigh_radical_depth: int = 2
    #: Numeric route: most masses whose fallback modes come from mpmath (beyond: spring-factor SVD).
    mpmath_modes: int = 16
    #: Printing: longest closed form a text report prints (characters, about two terminal lines).
    text_closed_form: int = 160
    #: Printing: longest closed form a ``--json`` field carries (characters; longer: null, with a note).
    json_closed_form: int = 4000


#: The caps in force.
CAPS = Caps()

__all__ = ["Caps", "CAPS"]
