"""The whole-run loop of the implicit steps (Newmark-β, HHT-α) on small ``[masses]`` scenes, as plain
Python over float arrays: a template compiled by :mod:`.cache` beside :mod:`.loops` (same conventions:
``force(x, t, out, p)`` writes ``a(x) + a_ext(t)``, frames at the step indices ``rec``, t = i·h).

The scheme is :mod:`numeric.integrators.newmark`'s, step for step: predictor ``x̃ = x + h v + (½ − β)h² a``,
``ṽ = v + (1 − γ)h a``; ``a₁`` from ``S a₁ = (1 + α)(f(x̃, t₁) + D ṽ) − α F₀`` with
``S = I − (1 + α)(βh² A + γh D)`` (``F₀ = f(x₀, t₀) + D v₀``, the force of the step below), factored
once (LAPACK's ``getrf``: ``lu``, ``piv``, passed in); cubic springs then Newton on the residual with
the tangent ``A(x) = −M⁻¹Bᵀdiag(k + 3k₃d²)B`` refactored per iteration (Gaussian elimination in place), and the
same stopping rule.
"""

import numpy as np


def _lu_solve(lu, piv, r, out):
    """``out = S⁻¹ r`` from LAPACK's ``getrf`` factors (row interchanges ``piv``, unit L, U)."""
    n = r.shape[0]
    for i in range(n):
        out[i] = r[i]
    for i in range(n):
        j = piv[i]
        if j != i:
            tmp = out[i]
            out[i] = out[j]
            out[j] = tmp
    for i in range(n):
        s = out[i]
        for c in range(i):
            s -= lu[i, c] * out[c]
        out[i] = s
    for i in range(n - 1, -1, -1):
        s = out[i]
        for c in range(i + 1, n):
            s -= lu[i, c] * out[c]
        out[i] = s / lu[i, i]


def _gauss_solve(S, r, out):
    """``out = S⁻¹ r`` by Gaussian elimination with partial pivoting, in place (S and r are overwritten;
    no allocation: the Newton iterations of an N ≤ 12 scene)."""
    n = r.shape[0]
    for c in range(n):
        piv = c
        big = abs(S[c, c])
        for i in range(c + 1, n):
            if abs(S[i, c]) > big:
                big = abs(S[i, c])
                piv = i
        if piv != c:
            for j in range(n):
                tmp = S[c, j]
                S[c, j] = S[piv, j]
                S[piv, j] = tmp
            tmp = r[c]
            r[c] = r[piv]
            r[piv] = tmp
        for i in range(c + 1, n):
            f = S[i, c] / S[c, c]
            if f != 0.0:
                for j in range(c + 1, n):
                    S[i, j] -= f * S[c, j]
                r[i] -= f * r[c]
    for i in range(n - 1, -1, -1):
        s = r[i]
        for j in range(i + 1, n):
            s -= S[i, j] * out[j]
        out[i] = s / S[i, i]


def _tangent_matrix(x, masses, ends, k, k3, D, c1, c2, S):
    """``S = I − c1·A(x) − c2·D`` with ``A(x) = −M⁻¹Bᵀdiag(k + 3k₃d²)B`` (``D`` empty: none)."""
    n = x.shape[0]
    for r in range(n):
        for c in range(n):
            S[r, c] = 0.0
        S[r, r] = 1.0
    for s in range(ends.shape[0]):
        a, b = ends[s, 0], ends[s, 1]
        xa = x[a] if a >= 0 else 0.0
        xb = x[b] if b >= 0 else 0.0
        d = xa - xb
        ks = k[s] + 3.0 * k3[s] * d * d
        # A[i, j] -= ks B_si B_sj / m_i; S = I - c1 A
        if a >= 0:
            S[a, a] += c1 * ks / masses[a]
        if b >= 0:
            S[b, b] += c1 * ks / masses[b]
        if a >= 0 and b >= 0:
            S[a, b] -= c1 * ks / masses[a]
            S[b, a] -= c1 * ks / masses[b]
    if D.shape[0]:
        for r in range(n):
            for c in range(n):
                S[r, c] -= c2 * D[r, c]


def _with_damping(f, v, D, out, scale):
    """``out = scale·(f + D v)`` (D empty: scale·f)."""
    n = f.shape[0]
    for r in range(n):
        s = f[r]
        if D.shape[0]:
            for c in range(n):
                s += D[r, c] * v[c]
        out[r] = scale * s


def newmark_loop(force, x0, v0, p, h, steps, rec, xs, vs, beta, gamma, alpha, lu, piv, D,
                 nonlinear, masses, ends, k, k3, max_newton):
    """The HHT-α / Newmark-β run (see the module docstring). Returns ``(force evaluations, failed step)``
    (failed step -1: every Newton iteration converged)."""
    n = x0.shape[0]
    x, v = x0.copy(), v0.copy()
    a, f, F0 = np.empty(n), np.empty(n), np.empty(n)
    xt, vt, rhs, a1, x1, v1, R, da = (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                                      np.empty(n), np.empty(n), np.empty(n))
    S = np.empty((n, n))
    force(x, 0.0, f, p)
    _with_damping(f, v, D, a, 1.0)
    for r in range(n):
        F0[r] = a[r]
    evals = 1
    ap = 1.0 + alpha
    bh2, gh = beta * h * h, gamma * h
    c1, c2 = ap * bh2, ap * gh
    hh_pred, h_pred = (0.5 - beta) * h * h, (1.0 - gamma) * h
    _store_frame(xs, vs, np.intp(0), x, v)
    j = np.intp(1)
    for i in range(steps):
        t1 = (i + 1) * h
        for r in range(n):
            xt[r] = x[r] + h * v[r] + hh_pred * a[r]
            vt[r] = v[r] + h_pred * a[r]
        force(xt, t1, f, p)
        evals += 1
        _with_damping(f, vt, D, rhs, ap)
        for r in range(n):
            rhs[r] -= alpha * F0[r]
        _lu_solve(lu, piv, rhs, a1)
        if nonlinear:
            scale = 1e-300
            for r in range(n):
                scale = max(scale, abs(a1[r]))
            prev = np.inf
            done = False
            for _it in range(max_newton):
                for r in range(n):
                    x1[r] = xt[r] + bh2 * a1[r]
                    v1[r] = vt[r] + gh * a1[r]
                force(x1, t1, f, p)
                evals += 1
                _with_damping(f, v1, D, R, ap)
                for r in range(n):
                    R[r] = a1[r] - R[r] + alpha * F0[r]
                _tangent_matrix(x1, masses, ends, k, k3, D, c1, c2, S)
                _gauss_solve(S, R, da)
                size = 0.0
                for r in range(n):
                    a1[r] -= da[r]
                    scale = max(scale, abs(a1[r]))
                    size = max(size, abs(da[r]))
                if size <= 1e-15 * scale or (size <= 1e-11 * scale and size >= 0.25 * prev):
                    done = True
                    break
                prev = size
            if not done:
                return evals, i
        for r in range(n):
            x[r] = xt[r] + bh2 * a1[r]
            v[r] = vt[r] + gh * a1[r]
            a[r] = a1[r]
        if alpha != 0.0:  # HHT keeps the force of this step for the next one
            force(x, t1, f, p)
            evals += 1
            _with_damping(f, v, D, F0, 1.0)
        if j < rec.shape[0] and rec[j] == i + 1:
            _store_frame(xs, vs, j, x, v)
            j += 1
    return evals, -1


def _store_frame(xs, vs, j, x, v):
    for r in range(x.shape[0]):
        xs[j, r] = x[r]
        vs[j, r] = v[r]


#: The loops this template exports, and the helpers they call (compiled by :mod:`.cache`).
LOOPS = ("newmark_loop",)
HELPERS = ("_lu_solve", "_gauss_solve", "_tangent_matrix", "_with_damping", "_store_frame")
