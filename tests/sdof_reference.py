"""An independent reference for response spectra: the damped oscillator

    ü + 2ζωu̇ + ω²u = −a(t),   u(t₀) = u̇(t₀) = 0,

driven by a record linear between its rows and zero after the last one, solved in closed form on
each row interval at 50+ digits (mpmath), with every extremum of u located exactly.

On an interval with input a(τ) = a_l + sτ the solution is u = p + w: p(τ) = c₀ + c₁τ with
c₁ = −s/ω², c₀ = −(a_l + 2ζωc₁)/ω², and w(τ) = e^{−ζωτ}(W₀ cos βτ + S sin βτ) (β = ω√(1−ζ²)),
written directly from the ODE. Writing w = E cos θ (θ = βτ − φ), ü = ẅ = −ω²E cos(θ + 2δ)
(sin δ = ζ), whose zeros are evenly spaced by π/β: u̇ is monotone between consecutive ones, so each
such piece holds at most one root of u̇, found by bisection to the working precision. The peak over
an interval is the largest |u| at its ends and at those roots. Nothing of springchain is used.

For the free vibration after the record (a = 0 from the end state) the same is done over
``tail_periods`` damped periods: for ζ > 0 the extrema of the free decay shrink, so the first
ones hold its peak; for ζ = 0 every cycle repeats the first.
"""

from __future__ import annotations

import mpmath as mp


class Segment:
    """The closed-form response on one interval of length h (input a_l + s·τ), from (u0, v0)."""

    def __init__(self, w, z, u0, v0, al, s):
        self.w, self.z = w, z
        self.alpha, self.beta = z * w, w * mp.sqrt(1 - z * z)
        self.c1 = -s / w**2
        self.c0 = -(al + 2 * z * w * self.c1) / w**2
        self.W0 = u0 - self.c0
        self.S = (v0 - self.c1 + self.alpha * self.W0) / self.beta
        self.al, self.s = al, s

    def u(self, t):
        return self.c0 + self.c1 * t + mp.exp(-self.alpha * t) * (self.W0 * mp.cos(self.beta * t)
                                                                  + self.S * mp.sin(self.beta * t))

    def du(self, t):
        e, c, s = mp.exp(-self.alpha * t), mp.cos(self.beta * t), mp.sin(self.beta * t)
        return self.c1 + e * ((self.beta * self.S - self.alpha * self.W0) * c
                              - (self.beta * self.W0 + self.alpha * self.S) * s)

    def ddu(self, t):
        """ü from the equation of motion."""
        return -2 * self.alpha * self.du(t) - self.w**2 * self.u(t) - (self.al + self.s * t)

    def curvature_zeros(self, lo, hi):
        """Times in (lo, hi) where ü = 0 (θ + 2δ = π/2 + mπ), ascending."""
        phi = mp.atan2(self.S, self.W0)
        delta = mp.asin(self.z)
        first = (mp.pi / 2 - 2 * delta + phi) / self.beta
        step = mp.pi / self.beta
        t = first + mp.ceil((lo - first) / step) * step
        out = []
        while t < hi:
            if t > lo:
                out.append(t)
            t += step
        return out

    def peak(self, h, window=None):
        """max |u| over [0, h] (or over ``window`` = (t_a, t_b) ⊂ [0, h]), exactly."""
        lo, hi = window or (mp.mpf(0), h)
        pts = [lo, *self.curvature_zeros(lo, hi), hi]
        best = max(abs(self.u(lo)), abs(self.u(hi)))
        d = [self.du(t) for t in pts]
        for i in range(len(pts) - 1):
            if d[i] == 0:
                best = max(best, abs(self.u(pts[i])))
            elif d[i] * d[i + 1] < 0:
                best = max(best, abs(self.u(_root(self.du, pts[i], pts[i + 1], d[i], self.ddu))))
        return best


def _root(f, lo, hi, flo, df=None):
    """The root of f in [lo, hi] (one sign change): Newton on ``df`` kept inside the bracket,
    bisection when it leaves it, to 2^-(precision - 24) (u there is off by its square)."""
    eps = mp.mpf(2) ** (-mp.mp.prec + 24)
    x = (lo + hi) / 2
    while hi - lo > eps * max(abs(hi), 1):
        fx = f(x)
        if fx == 0:
            return x
        if (fx > 0) == (flo > 0):
            lo, flo = x, fx
        else:
            hi = x
        step = fx / df(x) if df is not None else None
        if step is not None and abs(step) <= eps * max(abs(x), 1):
            return x - step
        nxt = x - step if step is not None else None
        x = nxt if nxt is not None and lo < nxt < hi else (lo + hi) / 2
    return (lo + hi) / 2


def _long_peak(seg: Segment, h, T, z, digits: int):
    """max |u| over an interval of very many periods, searched exactly only where it can be reached.

    ζ = 0: u = p + r·cos(ωτ − φ); at u̇ = 0, sin(ωτ − φ) = c₁/(rω), so successive local maxima (and
    minima) of u sit one period apart at the same phase and their values p(τₖ) + const are linear
    in k: the largest are the first or the last, inside [0, 2T] or [h − 2T, h].
    ζ > 0: past τ where the envelope E(τ) = r·e^{−ζωτ} is below 10^−digits of r, |u − p| ≤ E(τ)
    with p linear, so |u| there is within 2E(τ) of max(|u(τ)|, |u(h)|).
    """
    if z == 0:
        return max(seg.peak(h, (mp.mpf(0), 2 * T)), seg.peak(h, (h - 2 * T, h)))
    tau = digits * mp.log(10) / (z * 2 * mp.pi / T)
    if tau >= h:
        return seg.peak(h)
    return max(seg.peak(h, (mp.mpf(0), tau)), abs(seg.u(h)))


def sd(t, a, T, z, dps: int = 50, tail_periods: int = 3, long_cycles=None):
    """(SD, peak over the record alone, peak of the free vibration after it) of the record
    (t, a) (floats or decimal strings, read exactly) for period T and damping ratio z.

    Row intervals of more than ``long_cycles`` periods (default: none) are searched as
    :func:`_long_peak` says (for gaps of up to ~1e18 periods)."""
    with mp.workdps(dps):
        t = [mp.mpf(x) for x in t]
        a = [mp.mpf(x) for x in a]
        T, z = mp.mpf(T), mp.mpf(z)
        w = 2 * mp.pi / T
        u0 = v0 = mp.mpf(0)
        record = mp.mpf(0)
        for i in range(len(t) - 1):
            h = t[i + 1] - t[i]
            seg = Segment(w, z, u0, v0, a[i], (a[i + 1] - a[i]) / h)
            if long_cycles is not None and h > long_cycles * T:
                record = max(record, _long_peak(seg, h, T, z, dps - 10))
            else:
                record = max(record, seg.peak(h))
            u0, v0 = seg.u(h), seg.du(h)
        free = Segment(w, z, u0, v0, mp.mpf(0), mp.mpf(0))
        tail = free.peak(tail_periods * T / mp.sqrt(1 - z * z))
        return max(record, tail), record, tail


def end_state(t, a, T, z, dps: int = 50):
    """(u, u̇) at the record's last row."""
    with mp.workdps(dps):
        t = [mp.mpf(x) for x in t]
        a = [mp.mpf(x) for x in a]
        w = 2 * mp.pi / mp.mpf(T)
        u0 = v0 = mp.mpf(0)
        for i in range(len(t) - 1):
            h = t[i + 1] - t[i]
            seg = Segment(w, mp.mpf(z), u0, v0, a[i], (a[i + 1] - a[i]) / h)
            u0, v0 = seg.u(h), seg.du(h)
        return u0, v0
