"""The fast paths of issue 22: the seed's exact solution through the method protocol (the padded
cos/t·sinc table, the rigid basis of small systems) against an mpmath reference built from the
scene's TOML; the small-system rigid basis against an independent union-find; the compiled Verlet
loop of an undamped scene with a rigid mode against the NumPy driver and the exact solution; and
the progress phases sharing one thread."""

from __future__ import annotations

import io
import threading
import time

import mpmath as mp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers import TomlScene, free_pieces

from springchain.numeric import progress
from springchain.numeric.run import registry
from springchain.numeric.run.grid import Grid
from springchain.numeric.run.protocol import Options, record
from springchain.numeric.modes.spectrum import SMALL_PIECES, rigid_basis

EPS = float(np.finfo(float).eps)


def _mp_reference(seed_path, times):
    """x(t), v(t) of the seed from its TOML alone: ``exp(A t) z0`` in mpmath (40 digits) with
    ``A = [[0, I], [-M⁻¹K, 0]]`` assembled from the raw file; shape (len(times), N) each."""
    scene = TomlScene.read(seed_path)
    _, M, K, _ = scene.matrices()
    n = M.shape[0]
    x0, v0 = scene.data["initial"]["x"], scene.data["initial"]["v"]
    with mp.workdps(40):
        A = mp.zeros(2 * n, 2 * n)
        for i in range(n):
            A[i, n + i] = 1
            for j in range(n):
                A[n + i, j] = -mp.mpf(float(K[i, j])) / mp.mpf(float(M[i, i]))
        z0 = mp.matrix([mp.mpf(float(c)) for c in list(x0) + list(v0)])
        out = np.array([[float(c) for c in mp.expm(A * mp.mpf(float(t))) * z0] for t in times])
    return out[:, :n], out[:, n:]


def test_seed_exact_solution_matches_mpmath_from_the_toml(seed_path, seed_system):
    """The modal run on the benchmark's grid (S = 1001, the split route) to ~10 ulps of the motion,
    at times spread over the grid and in its last (padded) block."""
    scene = TomlScene.read(seed_path)
    x0 = np.array(scene.data["initial"]["x"], float)
    v0 = np.array(scene.data["initial"]["v"], float)
    grid = Grid(0.1, 1000, 1)
    run = record(registry.method("modal", Options(progress=False)), seed_system.fresh(), x0, v0, grid)
    rows = [0, 1, 31, 32, 33, 500, 977, 990, 999, 1000]
    xr, vr = _mp_reference(seed_path, grid.t[rows])
    scale = 1.0 + float(np.abs(xr).max())
    assert np.abs(run.x[rows] - xr).max() <= 64 * EPS * scale
    assert np.abs(run.v[rows] - vr).max() <= 64 * EPS * (1.0 + float(np.abs(vr).max()))
    # the rows are contiguous copies (a recorder's arrays), the motion is not trivial
    assert run.x.flags.c_contiguous and np.abs(run.x[-1] - x0).max() > 1.0


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 24), data=st.data())
def test_small_rigid_basis_matches_a_union_find(n, data):
    """Reachability by matrix squaring finds the same free pieces as a union-find of the test's own,
    columns in the same order, each the unit mass-weighted vector of its piece to 1 ulp."""
    springs = data.draw(st.lists(st.tuples(st.integers(-1, n - 1), st.integers(-1, n - 1))
                                 .filter(lambda e: e != (-1, -1)), max_size=2 * n))
    ends = np.array(springs, dtype=int).reshape(-1, 2)
    masses = 10.0 ** np.array(data.draw(st.lists(st.floats(-6, 6), min_size=n, max_size=n)))
    assert n <= SMALL_PIECES
    R = rigid_basis(masses, ends)
    pieces = sorted(free_pieces(n, ends), key=min)
    assert R.shape == (n, len(pieces))
    for j, piece in enumerate(pieces):
        expect = np.zeros(n)
        expect[piece] = np.sqrt(masses[piece]) / np.sqrt(np.sum(masses[piece]))
        assert np.abs(R[:, j] - expect).max() <= 4 * EPS
        assert np.all(R[[i for i in range(n) if i not in piece], j] == 0.0)


def test_compiled_verlet_on_the_seed(seed_system, reference, monkeypatch):
    """The undamped compiled loop (no damping helper in the loop) agrees with the NumPy driver to
    rounding and with the exact solution to the method's O(h²), rigid drift included."""
    pytest.importorskip("numba")
    import springchain.numeric.compiled.run as compiled_run

    monkeypatch.setattr(compiled_run, "COMPILE_MIN_EVALS", 0)
    method = registry.method("verlet", Options(progress=False))
    x0, v0 = reference["x0"], reference["v0"]
    grid = Grid(0.01, 5000, 50)
    fast = record(method, seed_system, x0, v0, grid)
    slow = record(method.with_options(Options(compiled=False, progress=False)), seed_system, x0, v0, grid)
    exact = record(registry.method("modal", Options(progress=False)), seed_system, x0, v0, grid)
    scale = max(np.abs(slow.x).max(), np.abs(slow.v).max())
    assert np.abs(fast.x - slow.x).max() <= 1e-12 * scale
    assert np.abs(fast.v - slow.v).max() <= 1e-12 * scale
    err = np.abs(fast.x - exact.x).max()
    assert 1e-8 < err < 1e-3  # Verlet's error at h = 0.01 over t = 50: order h², not rounding


def test_phases_share_one_thread_and_still_report():
    """Many short phases start no thread each; a long one on a terminal-less stream still prints
    its elapsed time, and nothing after it has ended."""
    before = threading.active_count()
    for _ in range(200):
        with progress.phase("short", stream=io.StringIO()):
            pass
    assert threading.active_count() <= before + 1
    log = io.StringIO()
    with progress.phase("long", stream=log) as rep:
        rep.t0 -= progress.PLAIN_INTERVAL + 1  # as if it had run past the quiet period
        deadline = time.monotonic() + 10.0
        while "long ..." not in log.getvalue() and time.monotonic() < deadline:
            time.sleep(0.05)
    text = log.getvalue()
    assert "long ..." in text and "done in" in text
    time.sleep(1.2)  # a tick later: an ended phase is not updated again
    assert log.getvalue() == text
