"""The accurate routes: each output's worst error by the accurate route and by the plain float64
route, and what each costs.

Run from the repository root (BLAS is pinned to one thread before NumPy loads)::

    python benchmarks/bench_accuracy.py [--json]

For each output, on scenes whose parameters span a contrast C = 1e4, 1e8, 1e12 (written here as
TOML, as a user would), it measures against the extended-precision references of
``tests/accuracy_reference.py`` (mpmath, assembled from the TOML's elements, checked at twice
the digits):

* **before** — the float64 route each output took until issue 18, rebuilt here from the generated
  module's matrices: LU of K − ω²M + iωC (frf); the augmented matrix exponential in physical
  coordinates with the constant load as a state (loaded exact solution); ``eigh_tridiagonal`` of D
  (index-dependent chains); ``eigvals(A, B)`` of the unbalanced linearisation (frf's ζ);
* **after** — the API (``springchain.frf``, ``simulate(methods=["modal"])``, ``modes``);

and times both side by side in this one process (minimum of repeats).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
import importlib.util

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

import accuracy_reference as ref  # noqa: E402

import springchain as sc  # noqa: E402
from springchain._api import _system  # noqa: E402

CONTRASTS = (1e4, 1e8, 1e12)


def _springs(contrast: float) -> list:
    """wall – x0 – x1 – x2 – x3: four springs log-spaced over the contrast, the softest at the wall."""
    k = np.geomspace(1 / np.sqrt(contrast), np.sqrt(contrast), 4)
    return [(-1, 0, k[0]), (0, 1, k[1]), (1, 2, k[2]), (2, 3, k[3])]


def _best(fn, repeats: int = 3) -> float:
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def _rel(got, want) -> float:
    return float(np.max(np.abs(np.asarray(got) - want) / np.abs(want)))


# -- frequency response -------------------------------------------------------------------------------------
def _plain_frf(system, omega, i, o):
    """Before: one complex LU of K − ω²M + iωC per frequency, from the module's float64 matrices."""
    mod, p = system.module, system.params
    K = np.asarray(mod.stiffness_matrix(**p), dtype=float)
    C = np.asarray(mod.damping_matrix(**p), dtype=float) if system.damped else 0 * K
    M = np.diag(system.masses)
    e = np.zeros(K.shape[0], dtype=complex)
    e[i] = 1
    Z = K[None] - (omega**2)[:, None, None] * M[None] + 1j * omega[:, None, None] * C[None]
    return np.linalg.solve(Z, np.broadcast_to(e, (omega.shape[0], e.shape[0]))[..., None])[:, o, 0]


def bench_frf(tmp: Path) -> list[dict]:
    from springchain.numeric.frf.response import frequency_response

    rows = []
    for c in CONTRASTS:
        text = ref.scene_text("frf", [1.0] * 4, _springs(c), [(3, -1, 0.01)])
        path = tmp / f"frf{c:.0e}.toml"
        path.write_text(text)
        r = sc.frf(path, input="x3", output="x3", transfer=False)
        system = _system(sc.load(path))[0]
        want = ref.receptance(ref.read(text), r.omega, 3, 3)
        H = r.magnitude * np.exp(1j * np.radians(r.phase))
        before = _plain_frf(system, r.omega, 3, 3)
        modes = [(x.omega_n, x.zeta, x.omega_d) for x in r.resonances]
        t_after = _best(lambda: frequency_response(system, 3, 3, r.omega[0], r.omega[-1], 400, modes))
        t_before = _best(lambda: _plain_frf(system, r.omega, 3, 3))
        rows.append({"output": "frf H (magnitude and phase)", "contrast": c, "points": int(r.omega.shape[0]),
                     "before": _rel(before, want), "after": _rel(H, want),
                     "seconds_before": t_before, "seconds_after": t_after})
    return rows


def bench_chain_frf() -> list[dict]:
    """Open chain of 1e5 masses: dynamic stiffness against the tridiagonal LU, per frequency."""
    from springchain.numeric.frf.response import Operator, _receptance_banded
    from springchain.numeric.frf.chain import chain_elements, chain_receptance

    n = 100_000
    rng = np.random.default_rng(1)
    m = 10.0 ** rng.uniform(-2, 2, n)
    k = 10.0 ** rng.uniform(-2, 2, n)
    ends = np.stack([np.arange(-1, n - 1), np.arange(n)], axis=1)
    el = chain_elements(m, ends, k)
    w = np.geomspace(1e-3, 10, 20)
    chain_receptance(el, w[:1], 0, n - 1)  # compile
    kd = k.copy()
    kd[:-1] += k[1:]
    op = Operator(m, (kd, -k[1:], 0.0), None, True)
    t_after = _best(lambda: chain_receptance(el, w, 0, n - 1)) / w.shape[0]
    t_before = _best(lambda: _receptance_banded(op, w, 0, n - 1)) / w.shape[0]
    return [{"output": "chain frf (n = 1e5), per frequency", "contrast": 1e4, "before": None, "after": None,
             "seconds_before": t_before, "seconds_after": t_after}]


# -- loaded exact solution -----------------------------------------------------------------------------------
def _plain_exact(system, x0, v0, t, h):
    """Before: exp(A t) of the physical augmented system, K and the constant load as float64 states."""
    mod, p, n = system.module, system.params, system.n
    minv = 1.0 / system.masses
    K = np.asarray(mod.stiffness_matrix(**p), dtype=float)
    C = np.asarray(mod.damping_matrix(**p), dtype=float) if system.damped else None
    const = np.asarray(mod.gravity_forces(**p), dtype=float) if hasattr(mod, "gravity_forces") else np.zeros(n)
    omegas, fc, fs = np.zeros(0), np.zeros((0, n)), np.zeros((0, n))
    if hasattr(mod, "forcing_harmonics"):
        omegas, fc, fs, c0 = (np.asarray(a, dtype=float) for a in mod.forcing_harmonics(**p))
        const = const + c0
    hh = omegas.shape[0]
    size = 2 * n + 2 * hh + 1
    A = np.zeros((size, size))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -minv[:, None] * K
    if C is not None:
        A[n:2 * n, n:2 * n] = -minv[:, None] * C
    for j in range(hh):
        ci, si = 2 * n + 2 * j, 2 * n + 2 * j + 1
        A[n:2 * n, ci], A[n:2 * n, si] = minv * fc[j], minv * fs[j]
        A[ci, si], A[si, ci] = -omegas[j], omegas[j]
    A[n:2 * n, -1] = minv * const
    z = np.concatenate([x0, v0, np.tile([1.0, 0.0], hh), [1.0]])
    Eh = scipy.linalg.expm(A * h)
    out = [z]
    for _ in range(t.shape[0] - 1):
        z = Eh @ z
        out.append(z)
    return np.array(out)[:, :n]


def bench_loaded(tmp: Path) -> list[dict]:
    from springchain.numeric.exact.linear import AugmentedLinear

    rows = []
    for label, damped in (("exact solution, gravity", False), ("exact solution, gravity + force + dashpots", True)):
        for c in CONTRASTS:
            dampers = [(3, -1, 0.003), (0, 1, 0.02)] if damped else []
            force = (1, 0.2, 0.5, 0.01) if damped else None
            dt = 2e2 if damped else 2e4
            text = ref.scene_text("hang", [1.0] * 4, _springs(c), dampers, gravity=9.81, force=force, dt=dt, steps=50)
            path = tmp / f"hang{int(damped)}{c:.0e}.toml"
            path.write_text(text)
            run = sc.simulate(path, methods=["modal"])
            scene = ref.read(text)
            m = np.array(scene.masses)
            const = m * 9.81
            harmonics = []
            if damped:
                const[1] += 0.2
                fc = np.zeros(4)
                fc[1] = 0.5
                harmonics = [(0.01, fc, np.zeros(4))]
            t = run.t[::5]
            want = ref.trajectory(scene, [0.0] * 4, [0.0] * 4, t, const=const, harmonics=harmonics)
            amp = np.max(np.abs(want))
            system = _system(sc.load(path))[0]
            x0 = np.zeros(4)
            before = _plain_exact(system, x0, x0, run.t, dt)[::5]
            t_after = _best(lambda: AugmentedLinear.from_system(system).solve(x0, x0, run.t, dt))
            t_before = _best(lambda: _plain_exact(system, x0, x0, run.t, dt))
            rows.append({"output": label, "contrast": c, "before": float(np.max(np.abs(before - want)) / amp),
                         "after": float(np.max(np.abs(run.x["modal"][::5] - want)) / amp),
                         "seconds_before": t_before, "seconds_after": t_after})
    return rows


# -- index-dependent chains -------------------------------------------------------------------------------------
def _chain_text(n, contrast_m, contrast_k, dt, steps):
    return (f'name = "ichain"\ndescription = "index-dependent chain"\n[parameters]\nm = 1.0\nk = 1.0\n'
            f"a = {float(contrast_m)!r}\nb = {float(contrast_k)!r}\n[chain]\nn = {n}\nmass = \"m*(1 + a*(i % 2))\"\n"
            f'k = "k*(1 + b*(i % 2))"\nleft = "wall"\nright = "free"\n'
            f'[initial]\nx = "0.01*sin(pi*(i + 1)/(n + 1)) + 0.003*cos(2.7*i)"\nv = "0"\n'
            f"[simulation]\ndt = {float(dt)!r}\nsteps = {steps}\n")


def _plain_chain(system, x0, t):
    """Before: eigh_tridiagonal of D formed in float64."""
    mod, p, n = system.module, system.params, system.n
    diag, off = (np.asarray(b, dtype=float) for b in mod.stiffness_bands(**p, n=n))
    r = np.sqrt(system.masses)
    w2, E = scipy.linalg.eigh_tridiagonal(diag / system.masses, off / (r[:-1] * r[1:]))
    w = np.sqrt(np.maximum(w2, 0.0))
    q0 = E.T @ (r * x0)
    return np.array([(E @ (q0 * np.cos(w * ti))) / r for ti in t])


def bench_chain(tmp: Path, n: int = 30) -> list[dict]:
    from springchain.numeric.exact.chain import ChainModal

    rows = []
    for c in CONTRASTS:
        a, b = np.sqrt(c), np.sqrt(c)  # mass and stiffness contrasts multiply in ω²
        path = tmp / f"chain{c:.0e}.toml"
        path.write_text(_chain_text(n, a, b, 2e3, 5))
        run = sc.simulate(path, methods=["modal"])
        system = _system(sc.load(path))[0]
        masses = [1.0 * (1 + a * (i % 2)) for i in range(n)]
        kk = lambda i: 1.0 * (1 + b * (i % 2))  # noqa: E731
        springs = [(-1, 0, kk(-1))] + [(i, i + 1, kk(i)) for i in range(n - 1)]
        x0 = run.x["modal"][0]
        want = ref.modal_trajectory(masses, springs, x0, np.zeros(n), run.t)
        amp = np.max(np.abs(want))
        before = _plain_chain(system, x0, run.t)
        rows.append({"output": f"index-dependent chain (n = {n}), exact method", "contrast": c,
                     "before": float(np.max(np.abs(before - want)) / amp),
                     "after": float(np.max(np.abs(run.x["modal"] - want)) / amp),
                     "seconds_before": _best(lambda: _plain_chain(system, x0, run.t)),
                     "seconds_after": _best(lambda: ChainModal.from_module(system.module, system.params, x0,
                                                                           np.zeros(n)).at(run.t))})
    # set-up cost at n = 2000 (the modes alone)
    from springchain.numeric.modes.chain import chain_spectrum

    big = tmp / "chain2000.toml"
    big.write_text(_chain_text(2000, 1e4, 1e4, 1.0, 2))
    system = _system(sc.load(big))[0]
    mod, p = system.module, system.params
    diag, off = (np.asarray(v, dtype=float) for v in mod.stiffness_bands(**p, n=2000))
    r = np.sqrt(system.masses)
    rows.append({"output": "index-dependent chain (n = 2000), modes set-up", "contrast": 1e8, "before": None,
                 "after": None,
                 "seconds_before": _best(lambda: scipy.linalg.eigh_tridiagonal(diag / system.masses,
                                                                               off / (r[:-1] * r[1:])), 1),
                 "seconds_after": _best(lambda: chain_spectrum(system.masses, system.spring_ends,
                                                               system.stiffness), 1)})
    return rows


# -- damping ratios -----------------------------------------------------------------------------------------
def bench_zeta(tmp: Path) -> list[dict]:
    rows = []
    for c in CONTRASTS:
        text = ref.scene_text("zeta", [1.0, 1.0, 1.0, 1.0], _springs(c), [(3, -1, 0.01), (0, 1, 0.3)])
        path = tmp / f"zeta{c:.0e}.toml"
        path.write_text(text)
        want = ref.damping_ratios(ref.read(text))
        system = _system(sc.load(path))[0]
        mod, p, n = system.module, system.params, system.n
        K, C = np.asarray(mod.stiffness_matrix(**p)), np.asarray(mod.damping_matrix(**p))

        def plain():
            A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
            B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), np.diag(system.masses)]])
            lam = scipy.linalg.eigvals(A, B)
            lam = lam[np.isfinite(lam)]
            osc = sorted((v for v in lam if v.imag > 1e-12 * np.max(np.abs(lam))), key=abs)
            return np.array([-v.real / abs(v) for v in osc])

        before = plain()
        r = sc.frf(path, input="x3", output="x3", transfer=False)
        after = np.array([x.zeta for x in r.resonances])
        modes = [m["damping_ratio"] for m in sc.modes(path).to_json()["modes"] if m["damping_ratio"]]
        from springchain.derive.damping_report import _damped_modes
        from springchain.derive.model import Model

        model = Model(sc.load(path))
        rows.append({"output": "frf resonance table ζ", "contrast": c,
                     "before": _rel(before, want) if before.shape == want.shape else float("inf"),
                     "after": _rel(after, want), "frf_equals_modes": bool(list(after) == modes),
                     "seconds_before": _best(plain), "seconds_after": _best(lambda: _damped_modes(model, None), 1)})
    return rows


def bench_modes_json(tmp: Path) -> list[dict]:
    path = tmp / "idx200k.toml"
    path.write_text(_chain_text(200_000, 1e6, 1e4, 0.1, 2))
    m = sc.modes(path)
    sc.load(path)
    from springchain._api import _chain_omega2

    t = _best(lambda: _chain_omega2(m.scene, m.modes), 1)
    t_all = _best(lambda: m.to_json(), 1)
    return [{"output": "modes --json, 2e5-mass index-dependent chain (20 modes)", "contrast": 1e10, "before": None,
             "after": None, "seconds_before": None, "seconds_after": t, "seconds_to_json": t_all}]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    _report.add_option(ap)
    args = ap.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        with tempfile.TemporaryDirectory() as d:
            tmp = Path(d)
            os.environ.setdefault("SPRINGCHAIN_CACHE", str(tmp / "cache"))
            rows = (bench_frf(tmp) + bench_chain_frf() + bench_loaded(tmp) + bench_chain(tmp) + bench_zeta(tmp)
                    + bench_modes_json(tmp))
        if args.json:
            print(json.dumps(rows, indent=1))
            return 0
        fmt = lambda v: "–" if v is None else f"{v:.2g}"  # noqa: E731
        print("| output | contrast | worst error, plain float64 route | accurate route | s plain | s accurate | cost |")
        print("|---|---|---|---|---|---|---|")
        for r in rows:
            cost = (f"{r['seconds_after'] / r['seconds_before']:.1f}×" if r.get("seconds_before") and r.get("seconds_after")
                    else "–")
            print(f"| {r['output']} | {r['contrast']:.0e} | {fmt(r['before'])} | {fmt(r['after'])} | "
                  f"{fmt(r.get('seconds_before'))} | {fmt(r.get('seconds_after'))} | {cost} |")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
