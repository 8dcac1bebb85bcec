"""The whole-run loops of small ``[masses]`` scenes, as plain Python over float arrays.

This file is a template, never run as it stands: :mod:`.cache` writes it (with
:mod:`.implicit_loops`) into one file keyed by its hash and compiles every function with
``numba.njit(cache=True)``, once for all scenes: a scene's force comes in as the loops' first
argument ``force``, a first-class function (the generated module's ``scalar_force`` compiled as a
``numba.cfunc``), so a new scene compiles only its force and a second process loads the loops from disk.

Conventions of every loop
-------------------------
``force(x, t, out, p)`` (float64 arrays, C-contiguous) writes ``a(x) + a_ext(t)`` into ``out`` (N,).
``Ad`` is ``-M⁻¹C`` (N, N), or shape (0, 0) without dampers; ``E = exp(Ad h/2)`` is the half damping flow of the
Strang splitting the fixed-step loops use (as :class:`numeric.run.effects.EffectSplitting`).
Frames are written into the preallocated ``xs``, ``vs`` (F, N) at the step indices ``rec``
(increasing, ``rec[0] = 0``); time is ``t = i·h`` at step i.
Integer constants handed to a helper, and counters that start from one, are ``np.intp(...)``:
numba compiles a helper once more for every literal integer it is called with.
"""

import numpy as np


def _half_damp(v, E, tmp):
    """``v ← E v`` in place (E shape (N, N); nothing when E is empty)."""
    n = E.shape[0]
    if n == 0:
        return
    for r in range(n):
        s = 0.0
        for c in range(n):
            s += E[r, c] * v[c]
        tmp[r] = s
    for r in range(n):
        v[r] = tmp[r]


def _store(xs, vs, j, x, v):
    for r in range(x.shape[0]):
        xs[j, r] = x[r]
        vs[j, r] = v[r]


def verlet_loop(force, x0, v0, p, h, steps, rec, xs, vs, E):
    """Velocity Verlet, ``x ← x + v h + a h²/2; a' = a(x); v ← v + (a + a') h/2`` (numeric.integrators.verlet)."""
    n = x0.shape[0]
    x, v = x0.copy(), v0.copy()
    a, an, tmp = np.empty(n), np.empty(n), np.empty(n)
    force(x, 0.0, a, p)
    hh, h2 = 0.5 * h * h, 0.5 * h
    _store(xs, vs, np.intp(0), x, v)
    damped = E.shape[0] > 0  # tested once: an undamped run then calls no damping helper (2x per step)
    j = np.intp(1)
    for i in range(steps):
        if damped:
            _half_damp(v, E, tmp)
        for r in range(n):
            x[r] = x[r] + h * v[r] + hh * a[r]
        force(x, (i + 1) * h, an, p)
        for r in range(n):
            v[r] = v[r] + h2 * (a[r] + an[r])
            a[r] = an[r]
        if damped:
            _half_damp(v, E, tmp)
        if j < rec.shape[0] and rec[j] == i + 1:
            _store(xs, vs, j, x, v)
            j += 1


def kahan_verlet_loop(force, x0, v0, p, h, steps, rec, xs, vs, E):
    """Kick–drift–kick Verlet with compensated sums of x and v (numeric.integrators.verlet_compensated)."""
    n = x0.shape[0]
    x, v = x0.copy(), v0.copy()
    a, tmp = np.empty(n), np.empty(n)
    cx, cv = np.zeros(n), np.zeros(n)
    force(x, 0.0, a, p)
    half = 0.5 * h
    _store(xs, vs, np.intp(0), x, v)
    damped = E.shape[0] > 0
    j = np.intp(1)
    for i in range(steps):
        if damped:
            _half_damp(v, E, tmp)
            cv[:] = 0.0
        for r in range(n):
            y = half * a[r] - cv[r]
            s = v[r] + y
            cv[r] = (s - v[r]) - y
            v[r] = s
        for r in range(n):
            y = h * v[r] - cx[r]
            s = x[r] + y
            cx[r] = (s - x[r]) - y
            x[r] = s
        force(x, (i + 1) * h, a, p)
        for r in range(n):
            y = half * a[r] - cv[r]
            s = v[r] + y
            cv[r] = (s - v[r]) - y
            v[r] = s
        if damped:
            _half_damp(v, E, tmp)
            cv[:] = 0.0
        if j < rec.shape[0] and rec[j] == i + 1:
            _store(xs, vs, j, x, v)
            j += 1


def splitting_loop(force, x0, v0, p, h, steps, rec, xs, vs, E, kicks, drifts, nodes):
    """A BAB splitting/composition method (numeric.integrators.splitting): ``kicks`` (s+1,) and ``drifts``
    (s,) already times h, ``nodes`` (s+1,) the kick times in units of h."""
    n = x0.shape[0]
    x, v = x0.copy(), v0.copy()
    a, tmp = np.empty(n), np.empty(n)
    force(x, 0.0, a, p)
    _store(xs, vs, np.intp(0), x, v)
    s = drifts.shape[0]
    damped = E.shape[0] > 0
    j = np.intp(1)
    for i in range(steps):
        if damped:
            _half_damp(v, E, tmp)
        for r in range(n):
            v[r] = v[r] + kicks[0] * a[r]
        for q in range(s):
            d, k = drifts[q], kicks[q + 1]
            for r in range(n):
                x[r] = x[r] + d * v[r]
            force(x, (i + nodes[q + 1]) * h, a, p)
            for r in range(n):
                v[r] = v[r] + k * a[r]
        if damped:
            _half_damp(v, E, tmp)
        if j < rec.shape[0] and rec[j] == i + 1:
            _store(xs, vs, j, x, v)
            j += 1


def _total(f, v, Ad, out):
    """``out = f + Ad v`` (Ad empty: f)."""
    n = f.shape[0]
    for r in range(n):
        out[r] = f[r]
    if Ad.shape[0]:
        for r in range(n):
            s = 0.0
            for c in range(n):
                s += Ad[r, c] * v[c]
            out[r] += s


def rk4_loop(force, x0, v0, p, h, steps, rec, xs, vs, E, Ad):
    """Classic RK4 on ``(x, v)' = (v, a(x) + a_ext(t) + Ad v)`` (numeric.integrators.rk4), inside the
    Strang splitting by ``E`` as the fixed-step runs do (pass one of E, Ad empty)."""
    n = x0.shape[0]
    x, v = x0.copy(), v0.copy()
    a = np.empty(n)
    k1, k2, k3, k4 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    x2, x3, x4, xt, f = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    force(x, 0.0, a, p)
    h2, h6 = 0.5 * h, h / 6.0
    _store(xs, vs, np.intp(0), x, v)
    damped = E.shape[0] > 0
    j = np.intp(1)
    for i in range(steps):
        t = i * h
        if damped:
            _half_damp(v, E, k4)
        _total(a, v, Ad, k1)
        for r in range(n):
            x2[r] = v[r] + h2 * k1[r]
            xt[r] = x[r] + h2 * v[r]
        force(xt, t + h2, f, p)
        _total(f, x2, Ad, k2)
        for r in range(n):
            x3[r] = v[r] + h2 * k2[r]
            xt[r] = x[r] + h2 * x2[r]
        force(xt, t + h2, f, p)
        _total(f, x3, Ad, k3)
        for r in range(n):
            x4[r] = v[r] + h * k3[r]
            xt[r] = x[r] + h * x3[r]
        force(xt, (i + 1) * h, f, p)
        _total(f, x4, Ad, k4)
        for r in range(n):
            x[r] = x[r] + h6 * (v[r] + 2.0 * (x2[r] + x3[r]) + x4[r])
            v[r] = v[r] + h6 * (k1[r] + 2.0 * (k2[r] + k3[r]) + k4[r])
        force(x, (i + 1) * h, a, p)
        if damped:
            _half_damp(v, E, k4)
        if j < rec.shape[0] and rec[j] == i + 1:
            _store(xs, vs, j, x, v)
            j += 1


def _rhs(force, y, t, p, Ad, out, f):
    """``out = (v, a(x) + a_ext(t) + Ad v)`` for ``y = (x, v)`` (2N,)."""
    n = y.shape[0] // 2
    force(y[:n], t, f, p)
    for r in range(n):
        out[r] = y[n + r]
    _total(f, y[n:], Ad, out[n:])


def dop853_loop(force, x0, v0, p, t0, t_end, rtol, atol, Ad, A, B, C, E3, E5, ts, max_steps, t_eval, xs, vs, D):
    """SciPy's DOP853 (``scipy.integrate.DOP853``: its tableau, initial step, error norm and step
    control, step for step) on the first-order system; the accepted step ends go into ``ts``
    (up to ``max_steps``). Frames at the increasing times ``t_eval`` (S,) (empty: none) go into
    ``xs``, ``vs`` (S, N) through SciPy's dense output (``solve_ivp(t_eval=...)``: three more stages
    of the extended tableau ``A``, ``C`` (16,) and ``D`` (4, 16), on the steps that hold an output
    time, counted in the evaluations). Returns ``(x, v, accepted, evaluations)``, or accepted = -1
    when the step size fell below SciPy's minimum."""
    n = x0.shape[0]
    m = 2 * n
    y = np.empty(m)
    for r in range(n):  # element loops, not slice assignment (whose shape check compiles string code)
        y[r] = x0[r]
        y[n + r] = v0[r]
    f = np.empty(m)
    g = np.empty(n)
    K = np.empty((16, m))
    F = np.empty((7, m))
    yo = np.empty(m)
    row = np.intp(0)
    _rhs(force, y, t0, p, Ad, f, g)
    evals = 1
    span = abs(t_end - t0)
    sc = np.empty(m)
    d0 = 0.0
    d1 = 0.0
    for r in range(m):
        sc[r] = atol + abs(y[r]) * rtol
        d0 += (y[r] / sc[r]) ** 2
        d1 += (f[r] / sc[r]) ** 2
    d0 = np.sqrt(d0 / m)
    d1 = np.sqrt(d1 / m)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, span)
    y1 = np.empty(m)
    f1 = np.empty(m)
    for r in range(m):
        y1[r] = y[r] + h0 * f[r]
    _rhs(force, y1, t0 + h0, p, Ad, f1, g)
    evals += 1
    d2 = 0.0
    for r in range(m):
        d2 += ((f1[r] - f[r]) / sc[r]) ** 2
    d2 = np.sqrt(d2 / m) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    h_abs = min(100 * h0, h1, span)
    t = t0
    yn = np.empty(m)
    ys = np.empty(m)
    accepted = 0
    expo = -1.0 / 8.0
    while t < t_end:
        min_step = 10 * abs(np.nextafter(t, np.inf) - t)
        if h_abs < min_step:
            h_abs = min_step
        ok = False
        rejected = False
        while not ok:
            if h_abs < min_step:
                return y[:n].copy(), y[n:].copy(), -1, evals
            t_new = t + h_abs
            if t_new - t_end > 0:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
            for r in range(m):
                K[0, r] = f[r]
            _rk_stages(force, y, ys, K, A, C, t, h, p, Ad, g, np.intp(1), np.intp(12))
            for r in range(m):
                acc = 0.0
                for q in range(12):
                    acc += K[q, r] * B[q]
                yn[r] = y[r] + h * acc
            _rhs(force, yn, t + h, p, Ad, K[12], g)
            evals += 12
            e5 = 0.0
            e3 = 0.0
            for r in range(m):
                s5 = 0.0
                s3 = 0.0
                for q in range(13):
                    s5 += K[q, r] * E5[q]
                    s3 += K[q, r] * E3[q]
                scale = atol + max(abs(y[r]), abs(yn[r])) * rtol
                e5 += (s5 / scale) ** 2
                e3 += (s3 / scale) ** 2
            if e5 == 0.0 and e3 == 0.0:
                err = 0.0
            else:
                err = abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * m)
            if err < 1:
                if err == 0:
                    factor = 10.0
                else:
                    factor = min(10.0, 0.9 * err ** expo)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                ok = True
            else:
                h_abs *= max(0.2, 0.9 * err ** expo)
                rejected = True
        if row < t_eval.shape[0] and t_eval[row] <= t_new:
            row = _dop853_dense(force, y, yn, f, K, t, h, p, Ad, A, C, D, g, ys, F, yo, t_eval, row, xs, vs)
            evals += 3
        t = t_new
        for r in range(m):
            y[r] = yn[r]
            f[r] = K[12, r]
        if accepted < max_steps:
            ts[accepted] = t
        accepted += 1
    return y[:n].copy(), y[n:].copy(), accepted, evals


def _rk_stages(force, y, ys, K, A, C, t, h, p, Ad, g, first, last):
    """Stages ``first … last-1`` of an explicit Runge–Kutta tableau (A, C): ``K[s] = f(t + C_s h,
    y + h Σ_q A[s, q] K[q])`` (``ys`` the work row)."""
    m = y.shape[0]
    for s in range(first, last):
        for r in range(m):
            acc = 0.0
            for q in range(s):
                acc += K[q, r] * A[s, q]
            ys[r] = y[r] + acc * h
        _rhs(force, ys, t + C[s] * h, p, Ad, K[s], g)


def _dop853_dense(force, y, yn, f, K, t, h, p, Ad, A, C, D, g, ys, F, yo, t_eval, row, xs, vs):
    """SciPy's DOP853 dense output on the accepted step ``t … t + h`` (``y`` → ``yn``, ``K[0]`` = f at t,
    ``K[12]`` at t + h): stages 13–15, the interpolant's rows ``F`` (7, 2N), and the frames at every
    ``t_eval[row:]`` inside the step (Dop853DenseOutput's Horner form). Returns the next row."""
    m = y.shape[0]
    n = m // 2
    _rk_stages(force, y, ys, K, A, C, t, h, p, Ad, g, np.intp(13), np.intp(16))
    for r in range(m):
        dy = yn[r] - y[r]
        F[0, r] = dy
        F[1, r] = h * K[0, r] - dy
        F[2, r] = 2.0 * dy - h * (K[12, r] + K[0, r])
        for i in range(4):
            acc = 0.0
            for q in range(16):
                acc += D[i, q] * K[q, r]
            F[3 + i, r] = h * acc
    t_new = t + h
    while row < t_eval.shape[0] and t_eval[row] <= t_new:
        x = (t_eval[row] - t) / h
        for r in range(m):
            acc = 0.0
            for i in range(7):
                acc += F[6 - i, r]
                if i % 2 == 0:
                    acc *= x
                else:
                    acc *= 1.0 - x
            yo[r] = acc + y[r]
        for r in range(n):
            xs[row, r] = yo[r]
            vs[row, r] = yo[n + r]
        row += 1
    return row


def _rkn_norm(dx, dv, sx, sv):
    """``sqrt((mean((dx/sx)²) + mean((dv/sv)²))/2)`` (the RKN pairs' error norm)."""
    n = dx.shape[0]
    ax = 0.0
    av = 0.0
    for r in range(n):
        ax += (dx[r] / sx[r]) ** 2
        av += (dv[r] / sv[r]) ** 2
    return np.sqrt(0.5 * (ax / n + av / n))


def rkn_loop(force, x0, v0, p, t_eval, rtol, atol, c, A, b, bp, e, ep, fsal, q_hat, order, xs, vs):
    """An embedded Runge–Kutta–Nyström pair with the step control of numeric.integrators.nystrom
    (Hairer–Nørsett–Wanner's first step, PI controller, stepping exactly onto every output time).
    Frames go into ``xs``, ``vs`` (S, N). Returns ``(evaluations, accepted steps)``; accepted = -1
    after a step-size underflow, -2 when the solution is not finite."""
    SAFETY, FAC_MAX, FAC_MIN, BETA1, BETA2 = 0.9, 4.0, 0.2, 0.7, 0.4
    n = x0.shape[0]
    s = c.shape[0]
    x, v = x0.copy(), v0.copy()
    K = np.empty((s, n))
    xi, xn, vn, ex, ev = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    sx, sv = np.empty(n), np.empty(n)
    t = t_eval[0]
    _store(xs, vs, np.intp(0), x, v)
    force(x, t, K[0], p)
    evals = 1
    # first step (numeric.integrators.nystrom.EmbeddedNystrom._first_step)
    span = t_eval[t_eval.shape[0] - 1] - t_eval[0]
    if span <= 0:
        h = 1.0
    else:
        for r in range(n):
            sx[r] = atol + rtol * abs(x[r])
            sv[r] = atol + rtol * abs(v[r])
        d0 = _rkn_norm(x, v, sx, sv)
        d1 = _rkn_norm(v, K[0], sx, sv)
        h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
        h0 = min(h0, span)
        for r in range(n):
            xi[r] = x[r] + h0 * v[r]
        force(xi, t + h0, vn, p)
        evals += 1
        for r in range(n):
            ex[r] = (vn[r] - K[0, r]) / h0
        d2 = _rkn_norm(K[0], ex, sx, sv)
        if max(d1, d2) <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
        h = min(100 * h0, h1, span)
    steps = 0
    k_ctrl = q_hat + 1.0
    err_prev = 1.0
    rejected = False
    for row in range(1, t_eval.shape[0]):
        target = t_eval[row]
        while t < target:
            clamped = h >= target - t
            hs = target - t if clamped else h
            if hs <= 1e-14 * max(abs(t), 1.0):
                return evals, -1
            h2 = hs * hs
            for i in range(1, s):
                for r in range(n):
                    acc = 0.0
                    for q in range(i):
                        acc += A[i, q] * K[q, r]
                    xi[r] = x[r] + (c[i] * hs) * v[r] + h2 * acc
                force(xi, t + c[i] * hs, K[i], p)
                evals += 1
            for r in range(n):
                sb = 0.0
                sbp = 0.0
                se = 0.0
                sep = 0.0
                for q in range(s):
                    sb += b[q] * K[q, r]
                    sbp += bp[q] * K[q, r]
                    se += e[q] * K[q, r]
                    sep += ep[q] * K[q, r]
                xn[r] = x[r] + hs * v[r] + h2 * sb
                vn[r] = v[r] + hs * sbp
                ex[r] = h2 * se
                ev[r] = hs * sep
                sx[r] = atol + rtol * max(abs(x[r]), abs(xn[r]))
                sv[r] = atol + rtol * max(abs(v[r]), abs(vn[r]))
            err = _rkn_norm(ex, ev, sx, sv)
            if not np.isfinite(err):
                return evals, -2
            if err <= 1.0:
                t = target if clamped else t + hs
                for r in range(n):
                    x[r] = xn[r]
                    v[r] = vn[r]
                steps += 1
                if fsal:
                    for r in range(n):
                        K[0, r] = K[s - 1, r]
                else:
                    force(x, t, K[0], p)
                    evals += 1
                err = max(err, 1e-10)
                grow = SAFETY * err ** (-BETA1 / k_ctrl) * err_prev ** (BETA2 / k_ctrl)
                grow = min(1.0 if rejected else FAC_MAX, max(FAC_MIN, grow))
                err_prev = err
                rejected = False
                h_next = hs * grow
                h = max(h, h_next) if clamped else h_next
            else:
                h = hs * max(FAC_MIN, SAFETY * err ** (-1.0 / k_ctrl))
                rejected = True
        _store(xs, vs, row, x, v)
    return evals, steps


#: The loops the compiled file exports (compiled with numba, cached on disk).
LOOPS = ("verlet_loop", "kahan_verlet_loop", "splitting_loop", "rk4_loop", "dop853_loop", "rkn_loop")
#: The helpers the loops call (compiled too).
HELPERS = ("_half_damp", "_store", "_total", "_rhs", "_rkn_norm", "_rk_stages", "_dop853_dense")
