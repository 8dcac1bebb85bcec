"""HHT's ``--alpha`` in simulate, plan and bench: one validation (springchain._api._method_settings),
the same refusals, and the setting reaching the method that plan and bench measure."""

from __future__ import annotations

import contextlib
import io

import pytest

from springchain.cli import main


def _run(argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
    return rc, err.getvalue().strip()


@pytest.mark.parametrize("argv", [["plan", "seed", "--tol", "1e-3"], ["bench", "--quick", "--no-progress"],
                                  ["simulate", "seed", "--method", "hht"]])
def test_alpha_out_of_range_is_refused_the_same_way(argv, tmp_path):
    rc, err = _run(argv + ["--alpha", "-0.5", "--out", str(tmp_path)] if argv[0] != "plan" else argv + ["--alpha", "-0.5"])
    assert rc == 2 and len(err.splitlines()) == 1
    assert "--alpha" in err and "-1/3 <= alpha <= 0" in err


def test_bench_refuses_alpha_without_hht(tmp_path):
    rc, err = _run(["bench", "--quick", "--no-progress", "--method", "verlet", "--alpha", "-0.1", "--out", str(tmp_path)])
    assert rc == 2 and "hht" in err and "verlet" in err


def test_plan_measures_hht_at_the_given_alpha():
    """The plan's hht candidate is the method with that alpha: more numerical damping (a more negative
    alpha) predicts a larger error at the same step."""
    from springchain import _api
    from springchain.numeric.plan.planner import Planner
    from springchain.numeric.run import registry
    from springchain._modules import system_of

    sc = _api.load("seed")
    system = system_of(sc)[0]
    errors = {}
    for alpha in (-0.02, -0.3):
        settings = _api._method_settings(alpha)
        planner = Planner.for_system(system, sc.x0, sc.v0, 20.0, 0.1, adaptive=False, settings=settings)
        hht = next(m for m in planner.step_methods if m.name == "hht")
        assert dict(hht.options.settings) == {"alpha": alpha}
        assert hht == registry.method("hht", hht.options)
        errors[alpha] = planner.predict_error(hht, 400)[0]
    assert errors[-0.3] > 1.2 * errors[-0.02]
