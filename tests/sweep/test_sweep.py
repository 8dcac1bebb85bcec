"""Issue 12: `springchain sweep` - distributions, reproducibility, resume, a killed worker, physics.

Real Dask clusters (LocalCluster, processes, 2 workers x 1 thread), small chains, few samples.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np
import pytest

import springchain
from springchain.cli import main
from springchain.numeric.sweep import driver as sweep_driver
from springchain.numeric.sweep.distributions import Dist, parse, parse_assignment
from springchain.numeric.errors import RunRefused
from springchain.numeric.sweep.realisations import SweepSpec, compute_batch

from helpers import chain_toml, one_line_error, run_cli, write_scene  # noqa: E402

pytest.importorskip("dask.distributed")
from dask.distributed import Client, LocalCluster  # noqa: E402



def chain_scene(tmp_path, n, name="dchain"):
    text = chain_toml(n, name=f"{name}{n}", parameters={"m": 1.0, "k": 1.0}, initial={"x": "0", "v": "0"},
                      simulation={"dt": 0.1, "steps": 10})
    return write_scene(tmp_path, f"{name}{n}", text)


def _cluster(workers):
    import logging

    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                        silence_logs=logging.CRITICAL)


@pytest.fixture(scope="module")
def client2():
    with _cluster(2) as cluster, Client(cluster) as client:
        yield client


def rows(result_or_out):
    out = getattr(result_or_out, "out", result_or_out)
    return sweep_driver.read(out).to_pydict()


# -- distributions --------------------------------------------------------------------------------
@pytest.mark.parametrize("text, kind, args", [
    ("uniform(0.5, 1.5)", "uniform", (0.5, 1.5)),
    (" normal( 1 ,0.1 ) ", "normal", (1.0, 0.1)),
    ("lognormal(-0.5, 2e-1)", "lognormal", (-0.5, 0.2)),
    ("grid(1, 2, 5)", "grid", (1.0, 2.0, 5.0)),
])
def test_parse_accepts(text, kind, args):
    d = parse(text)
    assert d == Dist(kind, args)
    assert parse(d.text) == d


@pytest.mark.parametrize("text, needle", [
    ("uniform(1, 0)", "a < b"),
    ("normal(1, 0)", "sigma > 0"),
    ("normal(1)", "takes 2 numbers"),
    ("grid(0, 1, 2.5)", "whole number"),
    ("gauss(0, 1)", "unknown distribution"),
    ("uniform(0, __import__('os'))", "not a number"),
    ("uniform(0, 1e999)", "not finite"),
    ("uniform 0 1", "not a distribution"),
])
def test_parse_refuses_naming_flag_and_accepted(text, needle):
    with pytest.raises(RunRefused) as exc:
        parse(text, "--vary m")
    msg = str(exc.value)
    assert "--vary m" in msg and needle in msg and "\n" not in msg


def test_parse_assignment():
    assert parse_assignment("m=uniform(1, 2)", "--vary", ("k", "m")) == ("m", Dist("uniform", (1.0, 2.0)))
    with pytest.raises(RunRefused, match="accepted: k, m"):
        parse_assignment("q=uniform(1, 2)", "--vary", ("k", "m"))
    with pytest.raises(RunRefused, match="NAME=DIST"):
        parse_assignment("uniform(1, 2)", "--vary")


def test_distribution_moments():
    rng = np.random.default_rng(0)
    for text in ("uniform(0.5, 1.5)", "normal(1, 0.2)", "lognormal(0.1, 0.3)"):
        d = parse(text)
        x = d.draw(rng, 200_000)
        assert abs(x.mean() - d.mean()) < 0.01 and abs(x.var() / d.variance() - 1) < 0.03


# -- realisations ---------------------------------------------------------------------------------
def _spec(tmp_path, n=50, disorder=(("mass", "normal(1, 0.6)"),), samples=40, seed=3):
    from springchain._modules import load_module

    sc = springchain.load(chain_scene(tmp_path, n))
    module, _ = load_module(sc)
    src = open(module.__file__, encoding="utf-8").read()
    return SweepSpec(sc.name, src, tuple(sorted(sc.parameters.items())), (),
                     tuple((w, parse(t)) for w, t in disorder), samples, seed)


def test_non_positive_draw_names_the_sample(tmp_path):
    spec = _spec(tmp_path)
    with pytest.raises(RunRefused) as exc:
        compute_batch(spec, 0, spec.total)
    msg = str(exc.value)
    assert msg.startswith("sample ") and "non-positive" in msg and "mass=normal(1.0, 0.6)" in msg
    # the named sample is the one that fails on its own, and the samples before it pass
    s = int(msg.split()[1].rstrip(":"))
    compute_batch(spec, 0, s)
    with pytest.raises(RunRefused, match=f"sample {s}:"):
        compute_batch(spec, s, s + 1)


def test_non_positive_draw_through_the_sweep(tmp_path, client2):
    scene = chain_scene(tmp_path, 30)
    with pytest.raises(RunRefused, match=r"^sample \d+: --disorder k=normal"):
        springchain.sweep(scene, disorder=["k=normal(1, 0.8)"], samples=20, batch=5, out=tmp_path / "o",
                          client=client2, progress=False)


def test_varied_parameter_non_positive(tmp_path, client2):
    with pytest.raises(RunRefused, match=r"^sample \d+: mass 0 = .* is not positive \(drawn m = "):
        springchain.sweep("seed", vary=["m=normal(0.2, 1)"], samples=20, batch=5, out=tmp_path / "o",
                          client=client2, progress=False)


def test_rows_do_not_depend_on_batching(tmp_path):
    spec = _spec(tmp_path, disorder=(("mass", "uniform(0.5, 1.5)"), ("k", "lognormal(0, 0.2)")), samples=7)
    whole = compute_batch(spec, 0, 7)
    parts = [compute_batch(spec, a, b) for a, b in ((0, 3), (3, 4), (4, 7))]
    for key in whole:
        np.testing.assert_array_equal(whole[key], np.concatenate([p[key] for p in parts]))


# -- the Dask sweep -------------------------------------------------------------------------------
def test_same_seed_same_rows_whatever_workers_and_batch(tmp_path, client2):
    """One worker (this process, Dask's synchronous scheduler) and two worker processes: the same rows."""
    scene = chain_scene(tmp_path, 60)
    kw = dict(vary=["k=uniform(0.8, 1.2)", "m=grid(1, 2, 3)"], disorder=["mass=uniform(0.5, 1.5)"], samples=4,
              seed=11, progress=False)
    a = springchain.sweep(scene, batch=5, out=tmp_path / "a", workers=1, **kw)
    b = springchain.sweep(scene, batch=2, out=tmp_path / "b", client=client2, figures=False, **kw)
    assert a.run["scheduler"].startswith("in-process") and b.run["scheduler"] == "an existing client"
    ra, rb = rows(a), rows(b)
    assert ra == rb
    assert ra["sample"] == list(range(12))
    assert sorted(set(ra["m"])) == [1.0, 1.5, 2.0] and ra["m"][:4] == [1.0] * 4
    assert set(ra) == {"sample", "k", "m", "omega2", "participation_ratio", "inverse_localisation_length"}
    assert all(len(w) == 60 and np.all(np.diff(w) >= 0) and w[0] == 0.0 for w in ra["omega2"])
    c = springchain.sweep(scene, batch=5, out=tmp_path / "c", workers=1, figures=False, **dict(kw, seed=12))
    assert rows(c)["omega2"] != ra["omega2"]
    summary = json.loads((a.out / "summary.json").read_text())
    assert summary["samples"] == 12 and len(summary["omega2"]["mean"]) == 60
    assert set(summary["omega2"]["quantiles"]) == {"0.05", "0.25", "0.5", "0.75", "0.95"}
    assert (a.out / "omega-distribution.png").stat().st_size > 0 and (a.out / "localisation.png").exists()


def test_resume_skips_finished_batches_and_completes_partial(tmp_path, client2):
    scene = chain_scene(tmp_path, 40)
    kw = dict(disorder=["mass=uniform(0.5, 1.5)"], samples=10, batch=3, seed=5, out=tmp_path / "o",
              client=client2, progress=False)
    first = springchain.sweep(scene, **kw)
    assert first.run["computed"] == 4
    before = rows(first)
    stamps = {p.name: p.stat().st_mtime_ns for p in (*first.figures, first.out / "summary.json")}
    again = springchain.sweep(scene, **kw)
    assert again.run == dict(again.run, computed=0, skipped=4)
    assert rows(again) == before
    # nothing new: the summary and figures on disk are the answer, not drawn again
    assert again.summary == first.summary and again.figures == first.figures
    assert {p.name: p.stat().st_mtime_ns for p in (*again.figures, again.out / "summary.json")} == stamps
    first.figures[1].unlink()  # a figure the user deleted is drawn again
    assert springchain.sweep(scene, **kw).figures[1].is_file()
    for b in (1, 3):
        sweep_driver.part_path(first.out, b).unlink()
    partial = springchain.sweep(scene, **kw)
    assert partial.run["computed"] == 2 and rows(partial) == before
    assert sorted(p.name for p in (first.out / "sweep.parquet").iterdir()) == [
        f"part-00000{b}.parquet" for b in range(4)]
    with pytest.raises(RunRefused, match=r"^--out .*different settings \(seed: 5 there, 6 now\)"):
        springchain.sweep(scene, **dict(kw, seed=6))


def test_killed_worker_loses_no_sample(tmp_path):
    """Kill a worker process of a real LocalCluster mid-run: every sample exactly once."""
    from springchain._sweep import sweep as api_sweep  # noqa: F401  (the same code path below)
    from springchain.numeric.sweep.realisations import SweepSpec as Spec

    spec = _spec(tmp_path, n=500, disorder=(("mass", "uniform(0.5, 1.5)"),), samples=40, seed=9)
    assert isinstance(spec, Spec)
    out = tmp_path / "fault"
    out.mkdir()
    killed = []
    with _cluster(2) as cluster, Client(cluster) as client:
        pids = client.run(os.getpid)

        def kill_one(b):
            if killed:
                return
            busy = [w for w, keys in client.processing().items() if keys]
            victim = busy[0] if busy else next(iter(pids))
            os.kill(pids[victim], 9)
            killed.append(victim)

        run = sweep_driver.run(spec, out, 2, client, progress=False, on_batch=kill_one)
    assert killed and run["computed"] == 20
    got = rows(out)
    assert got["sample"] == list(range(40))  # each sample exactly once, in order
    ref = compute_batch(spec, 0, 40)
    np.testing.assert_array_equal(np.array(got["omega2"]), ref["omega2"])


# -- physics -------------------------------------------------------------------------------------
def transfer_matrix_gamma(masses, k, omegas):
    """Lyapunov exponent of the product of 2x2 transfer matrices (QR re-orthogonalisation), per site."""
    g = []
    for w in omegas:
        v = np.array([1.0, 0.3])
        total = 0.0
        # (u_{i+1}, u_i) = [[2 - m_i w^2 / k, -1], [1, 0]] (u_i, u_{i-1}) in blocks of 16 sites
        a = 2.0 - masses * w * w / k
        for start in range(0, len(a), 16):
            T = np.eye(2)
            for ai in a[start:start + 16]:
                T = np.array([[ai, -1.0], [1.0, 0.0]]) @ T
            v = T @ v
            nv = np.linalg.norm(v)
            total += np.log(nv)
            v /= nv
        g.append(total / len(a))
    return np.array(g)


def test_matsuda_ishii_constant_against_transfer_matrix():
    from springchain.numeric.sweep.summary import matsuda_ishii

    rng = np.random.default_rng(2024)
    masses = rng.uniform(0.5, 1.5, 60_000)
    omegas = np.linspace(0.2, 0.4, 6)
    g = transfer_matrix_gamma(masses, 1.0, omegas)
    law = matsuda_ishii(omegas**2, k=1.0, mbar=1.0, sigma2=1 / 12)
    assert abs(np.mean(g / law) - 1) < 0.15


def test_sweep_localisation_matches_transfer_matrix(tmp_path, client2):
    """The sweep's γ at low ω (mass disorder) against an independent transfer-matrix Lyapunov exponent."""
    scene = chain_scene(tmp_path, 800)
    res = springchain.sweep(scene, disorder=["mass=uniform(0.5, 1.5)"], samples=16, batch=4, seed=1,
                            out=tmp_path / "phys", client=client2, progress=False, figures=False)
    law = res.summary["matsuda_ishii"]
    assert law["k"] == 1.0 and law["mbar"] == 1.0 and abs(law["sigma2"] - 1 / 12) < 1e-15
    t = rows(res)
    w = np.sqrt(np.array(t["omega2"]))
    g = np.array(t["inverse_localisation_length"])
    band = (w > 0.3) & (w < 0.7)
    sweep_ratio = np.mean(g[band]) / np.mean(w[band] ** 2)  # γ / ω² in the band
    rng = np.random.default_rng(77)
    omegas = np.linspace(0.3, 0.7, 6)
    tm = transfer_matrix_gamma(rng.uniform(0.5, 1.5, 40_000), 1.0, omegas)
    tm_ratio = np.mean(tm / omegas**2)
    assert abs(sweep_ratio / tm_ratio - 1) < 0.2, (sweep_ratio, tm_ratio)
    assert abs(tm_ratio / (law["sigma2"] / (8 * law["k"] * law["mbar"])) - 1) < 0.2
    # participation ratios: extended at low ω, localised near the band edge
    pr = np.array(t["participation_ratio"])
    assert np.mean(pr[(w > 0) & (w < 0.2)]) > 0.4 > 0.1 > np.mean(pr[w > 1.9])


# -- command line --------------------------------------------------------------------------------
@pytest.mark.parametrize("argv, needle", [
    (["seed", "--vary", "m=uniform(2, 1)", "--samples", "3"], "--vary m 'uniform(2, 1)': uniform(a, b) needs a < b"),
    (["seed", "--vary", "q=uniform(1, 2)", "--samples", "3"], "'q' is not accepted here; accepted: k, m"),
    (["seed", "--disorder", "mass=uniform(0.5, 1.5)", "--samples", "3"], "is not a [chain] scene"),
    (["seed", "--samples", "0"], "--samples '0': accepted: a whole number > 0"),
    (["seed", "--samples", "3", "--workers", "1", "--scheduler", "tcp://x:1"], "not allowed with argument"),
    (["seed", "--samples", "3", "--scheduler", "nowhere"], "--scheduler 'nowhere': accepted: an address"),
])
def test_cli_errors_are_one_line(argv, needle, capsys, tmp_path):
    one_line_error(*run_cli(["sweep", *argv, "--out", tmp_path / "o"], capsys), needle)


def test_cli_json(tmp_path, capsys):
    scene = chain_scene(tmp_path, 20)
    code = main(["sweep", str(scene), "--disorder", "mass=lognormal(0, 0.3)", "--samples", "6", "--batch", "4",
                 "--workers", "1", "--out", str(tmp_path / "cli"), "--json", "--no-progress", "--no-figures"])
    cap = capsys.readouterr()
    assert code == 0
    doc = json.loads(cap.out)
    assert doc["rows"] == 6 and doc["batches"] == 2 and doc["computed_batches"] == 2
    assert doc["figures"] == [] and not list((tmp_path / "cli").glob("*.png"))  # --no-figures
    assert json.loads((tmp_path / "cli" / "summary.json").read_text())["samples"] == 6
    assert doc["settings"]["disorder"] == ["mass=lognormal(0.0, 0.3)"] and doc["settings"]["seed"] == 0
    assert rows(tmp_path / "cli")["sample"] == list(range(6))


def test_figures_false_writes_no_figure_and_a_later_run_draws_them(tmp_path):
    """figures=False: parquet and summary.json only; resumed with figures, nothing is computed again
    and the figures are drawn from the parts on disk; resumed without, the summary is kept."""
    scene = chain_scene(tmp_path, 12)
    kw = dict(disorder=["k=uniform(0.9, 1.1)"], samples=4, workers=1, out=tmp_path / "o", progress=False)
    bare = springchain.sweep(scene, figures=False, **kw)
    assert bare.figures == () and bare.run["summary"] == "written" and not list(bare.out.glob("*.png"))
    drawn = springchain.sweep(scene, **kw)
    assert drawn.run["computed"] == 0 and drawn.run["summary"] == "written"
    assert [p.name for p in drawn.figures] == ["omega-distribution.png", "localisation.png"]
    assert all(p.stat().st_size > 0 for p in drawn.figures) and drawn.summary == bare.summary
    kept = springchain.sweep(scene, figures=False, **kw)
    assert kept.run["summary"] == "kept" and kept.figures == () and kept.summary == bare.summary


def test_cli_says_kept_when_a_resumed_sweep_had_nothing_to_do(tmp_path, capsys):
    scene = chain_scene(tmp_path, 12)
    argv = ["sweep", str(scene), "--disorder", "k=uniform(0.9, 1.1)", "--samples", "4", "--workers", "1",
            "--out", str(tmp_path / "o"), "--no-progress"]
    assert main(argv) == 0
    first = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in first[1:]] == ["wrote"] * 4  # parquet, summary, two figures
    assert main(argv) == 0
    again = capsys.readouterr().out.splitlines()
    assert "0 batches computed" in again[0]
    assert [line.split()[0] for line in again[1:]] == ["kept"] * 4
    assert [line.split()[1] for line in again[1:]] == [line.split()[1] for line in first[1:]]


def test_progress_lines(capsys):
    prog = sweep_driver.Progress(100, every=0.0)
    prog.add(10)
    time.sleep(0.01)
    prog.add(90, force=True)
    err = capsys.readouterr().err.splitlines()
    assert err and err[-1].startswith("sweep: 100/100 samples")


def test_worker_side_needs_no_sympy(repo_root):
    """What a worker runs (distributions, realisations, driver, summary) imports no SymPy."""
    import subprocess
    import sys

    code = ("import sys; sys.modules['sympy'] = None\n"
            "from pathlib import Path\n"
            "import springchain.generated.seed as g\n"
            "from springchain.numeric.sweep import driver as sweep_driver, summary as sweep_summary\n"
            "from springchain.numeric.sweep.distributions import parse\n"
            "from springchain.numeric.sweep.realisations import SweepSpec, compute_batch\n"
            "spec = SweepSpec('seed', Path(g.__file__).read_text(), tuple(sorted(g.DEFAULTS.items())),\n"
            "                 (('k', parse('uniform(1, 2)')),), (), 3, 0)\n"
            "print(compute_batch(spec, 0, 3)['omega2'].shape)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=repo_root, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "(3, 3)"


def test_existing_cluster_via_scheduler_address(tmp_path):
    """`dask scheduler` + `dask worker` as separate processes (the README's two shells); same rows."""
    import shutil
    import subprocess
    import sys

    dask_cli = shutil.which("dask") or str(Path(sys.executable).parent / "dask")
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([dask_cli, "scheduler", "--scheduler-file", str(sched_file), "--port", "0",
                               "--dashboard-address", ":0"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(300):
            if sched_file.exists() and sched_file.stat().st_size:
                break
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen([dask_cli, "worker", address, "--nworkers", "1", "--nthreads", "1",
                                       "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        scene = chain_scene(tmp_path, 30)
        kw = dict(disorder=["mass=uniform(0.5, 1.5)"], samples=6, batch=4, seed=2, progress=False, figures=False)
        ref = springchain.sweep(scene, out=tmp_path / "ref", workers=1, **kw)  # while the worker starts
        ext = springchain.sweep(scene, scheduler=address, out=tmp_path / "ext", **kw)
        assert rows(ext) == rows(ref) and len(rows(ext)["sample"]) == 6
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
