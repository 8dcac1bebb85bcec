"""Loads (issue 11): tabulated forces, ground motion, and forces on [chain] scenes.

Every trajectory is checked against an independent reference assembled here from the scene
file's own text (tomllib, SymPy for its expressions, ``np.interp`` for its CSV tables, read with
``np.loadtxt``) and integrated by solve_ivp DOP853 at rtol 1e-12, piece by piece between the
tables' rows (where the input has kinks).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import sympy
from scipy.integrate import solve_ivp

import helpers
import springchain as sc
from helpers import WALL_THREE, TomlScene, assemble, chain_toml, scene_toml, write_scene
from springchain._modules import derive, load_module
from springchain.cli import main
from springchain.derive.errors import SceneError
from springchain.derive.model import Effect, Model
from springchain.derive.scene import load_scene
from springchain.numeric.run.simulate import run_methods
from springchain.numeric.system import System

ROOT = Path(__file__).resolve().parents[2]


# -- scenes ---------------------------------------------------------------------------------------


FORCE_TABLE = "t,f\n0,0\n0.7,1.2\n1.9,-0.8\n3.1,0.4\n4.0,0\n"
# a ground record that starts and ends at rest and jumps nowhere (order 2 of Verlet holds)
GROUND_TABLE = "t,a\n0,0\n0.5,1.0\n1.2,-1.5\n2.0,0.8\n2.9,-0.3\n3.5,0\n"
# jumps at both ends (zero outside): the exact method resolves them, Verlet is then order 1
JUMP_TABLE = "t,f\n0.95,2.0\n2.45,1.0\n"


def write(tmp_path: Path, text: str, tables: dict[str, str] | None = None, name: str = "load") -> Path:
    return write_scene(tmp_path, name, text, tables)


def masses_text(name: str, extra: str) -> str:
    return scene_toml(name, {"m": 1.5, "k": 4.0, "c": 0.3, "A": 0.5, "W": 1.3, "F0": 0.7}, **WALL_THREE, extra=extra,
                      initial={"x": [0.0, 0.05, -0.02], "v": [0.01, 0.0, 0.0]}, simulation={"dt": 0.01, "steps": 600})


def chain_text(name: str, extra: str, n: int = 7) -> str:
    return chain_toml(n, "wall", "free", name=name, parameters={"m": 1.0, "k": 4.0, "F0": 0.3, "A": 0.4},
                      mass="m*(1 + 0.1*i)", k="k*(1 + 0.05*i)", simulation={"dt": 0.01, "steps": 600}, extra=extra)


def masses_scene(tmp_path, extra, tables=None, name="load"):
    return write(tmp_path, masses_text(name, extra), tables, name)


def chain_scene(tmp_path, extra, tables=None, name="cload"):
    return write(tmp_path, chain_text(name, extra), tables, name)


# -- an independent reference, built from the TOML text and CSV files only -------------------------
def reference(path: Path):
    """(rhs(t, z), n, knots, a_g(t), x_g(t) or None) of z = (x, v) relative to the ground."""
    toml = TomlScene.read(path)
    data, num, fun_t, t = toml.data, toml.value, toml.of_t, toml.t
    if "chain" in data:
        ch = data["chain"]
        n = int(ch["n"])
        m = np.array([num(ch["mass"], i=j) for j in range(n)])
        springs = [((j, j + 1), num(ch["k"], i=j)) for j in range(n - 1)]
        if ch.get("left") == "wall":
            springs.insert(0, ((-1, 0), num(ch["k"], i=-1)))
        if ch.get("right") == "wall":
            springs.append(((n - 1, -1), num(ch["k"], i=n - 1)))
        idx = None
    else:
        idx = toml.mass_index()
        m = np.array([num(e) for e in data["masses"].values()])
        n = len(m)
        springs = [(tuple(idx[e] for e in s["between"]), num(s["k"])) for s in data["springs"]]
    dampers = [(tuple(idx[e] for e in d["between"]), num(d["c"])) for d in data.get("dampers", [])]
    K = assemble(n, springs)
    C = assemble(n, dampers)
    loads, knots = [], [np.zeros(0)]
    for f in data.get("forces", []):
        on = f["on"] if idx is None else idx[f["on"]]
        if "f" in f:
            loads.append((on, fun_t(f["f"])))
        else:
            tt, ff = toml.csv(f["table"])
            knots.append(tt)
            loads.append((on, lambda s, tt=tt, ff=ff: np.interp(s, tt, ff, left=0.0, right=0.0)))
    a_g, x_g = (lambda s: 0.0), None
    if "ground" in data:
        g = data["ground"]
        if "acceleration" in g:
            a_g = fun_t(g["acceleration"])
            expr = toml.expr(g["acceleration"])
            s_ = sympy.Symbol("s")
            vg = sympy.integrate(expr.subs(t, s_), (s_, 0, t))
            x_g = sympy.lambdify(t, sympy.integrate(vg.subs(t, s_), (s_, 0, t)), "numpy")
        else:
            tt, aa = toml.csv(g["table"])
            knots.append(tt)
            a_g = lambda s, tt=tt, aa=aa: np.interp(s, tt, aa, left=0.0, right=0.0)  # noqa: E731

    def applied(s):
        f = np.zeros(n)
        for on, fn in loads:
            f[on] += float(fn(s))
        return f

    g = num(data["gravity"]["g"]) if "gravity" in data else 0.0

    def rhs(s, z):
        x, v = z[:n], z[n:]
        return np.concatenate([v, (-K @ x - C @ v + applied(s)) / m + g - float(a_g(s))])

    def absolute_acceleration(s, x, v):
        return (-K @ x - C @ v + applied(s)) / m + g

    return rhs, n, np.unique(np.concatenate(knots)), a_g, x_g, absolute_acceleration


def dop853_piecewise(rhs, n, x0, v0, t, knots):
    """DOP853 piece by piece between the inputs' kinks, evaluated at ``t``."""
    cuts = np.union1d([t[0], t[-1]], knots[(knots > t[0]) & (knots < t[-1])])
    z = np.concatenate([x0, v0])
    out = np.empty((t.shape[0], 2 * n))
    out[0] = z
    for a, b in zip(cuts[:-1], cuts[1:]):
        inside = (t > a) & (t <= b)
        sol = solve_ivp(rhs, (a, b), z, method="DOP853", rtol=1e-12, atol=1e-15,
                        t_eval=np.union1d(t[inside], [b]))
        assert sol.success
        out[inside] = sol.y[:, :int(inside.sum())].T
        z = sol.y[:, -1]
    return out[:, :n], out[:, n:]


def scene_and_system(path: Path):
    scene = load_scene(path)
    return scene, helpers.system_of(scene)[1]


# -- the scene language ---------------------------------------------------------------------------
def test_tabulated_force_and_ground_are_derived_as_traced_terms(tmp_path):
    path = masses_scene(tmp_path, '[[forces]]\non = "m2"\ntable = "f.csv"\n[ground]\nacceleration = "A*sin(W*t)"\n',
                        {"f.csv": FORCE_TABLE})
    model = Model(load_scene(path))
    t = model.t
    m = model.params["m"]
    a_g = sympy.Function("a_g")(t)
    ground = [tm for tm in model.terms if tm.effect is Effect.GROUND]
    assert [(tm.key, tm.coordinate) for tm in ground] == [("ground", 0), ("ground", 1), ("ground", 2)]
    assert [sympy.simplify(tm.force - e) for tm, e in zip(ground, (-m * a_g, -2 * m * a_g, -m * a_g))] == [0, 0, 0]
    (table,) = [tm for tm in model.terms if tm.effect is Effect.TABLE]
    assert (table.key, table.coordinate) == ("forces[0]", 1)
    assert table.force == sympy.Function("f_table0")(t)
    el = model.euler_lagrange()
    k = model.params["k"]
    x = model.x
    assert sympy.expand(el[1] - (2 * m * model.a[1] + k * (x[1] - x[0]) + 2 * k * (x[1] - x[2])
                                 - sympy.Function("f_table0")(t) + 2 * m * a_g)) == 0
    # ground displacement: x_g'' = a_g, x_g(0) = v_g(0) = 0
    vg, xg = model.ground_motion
    A, W = model.params["A"], model.params["W"]
    assert sympy.simplify(sympy.diff(xg, t, 2) - A * sympy.sin(W * t)) == 0
    assert sympy.simplify(xg.subs(t, 0)) == 0 and sympy.simplify(vg.subs(t, 0)) == 0
    assert sympy.simplify(sympy.diff(xg, t) - vg) == 0


def test_generated_code_holds_only_the_loads_own_code_and_no_table_data(tmp_path):
    plain = derive(load_scene(masses_scene(tmp_path, "", name="plain"))).source
    table = "t,f\n0,0\n1.5,1234.5678\n3,0\n"
    loaded = derive(load_scene(masses_scene(tmp_path, '[[forces]]\non = "m2"\ntable = "secret.csv"\n',
                                            {"secret.csv": table}, name="plain"))).source
    assert "1234.5678" not in loaded and "secret" not in loaded

    def defs(src):
        """Each function's text (header and indented body), by name."""
        out = {}
        for block in re.split(r"(?m)^(?=def )", src)[1:]:
            lines = block.splitlines()
            cut = next((j for j, ln in enumerate(lines[1:], 1) if ln and not ln.startswith(" ")), len(lines))
            out[lines[0].split("(")[0]] = "\n".join(lines[:cut]).rstrip()
        return out

    a, b = defs(plain), defs(loaded)
    assert set(b) - set(a) == {"def table_acceleration"}
    assert all(a[name] == b[name] for name in a)
    # no ground names in a scene without [ground] (scalar_force's docstring says what it sums, ground included)
    assert "GROUND" not in loaded and "ground_" not in plain
    ground = derive(load_scene(masses_scene(tmp_path, '[ground]\nacceleration = "A*sin(W*t)"\n',
                                            name="plain"))).source
    assert set(defs(ground)) - set(a) == {"def ground_acceleration", "def ground_harmonics", "def ground_motion"}
    assert "TABLE" not in ground and "table_" not in ground


def test_chain_generated_code_without_loads_is_unchanged(tmp_path):
    plain = derive(load_scene(chain_scene(tmp_path, "", name="cplain"))).source
    loaded = derive(load_scene(chain_scene(tmp_path, '[[forces]]\non = 3\nf = "F0*cos(t)"\n',
                                           name="cplain"))).source
    for line in plain.splitlines():
        if not line.startswith(("# GENERATED", "SCENE_SHA256", "EFFECTS")):
            assert line in loaded
    assert "def external_acceleration" in loaded and "def external_acceleration" not in plain


# -- exact and Verlet against the independent reference --------------------------------------------
CASES = {
    "table-force-damped": ('[[dampers]]\nbetween = ["m1", "m3"]\nc = "c"\n[[forces]]\non = "m2"\ntable = "f.csv"\n'
                           '[[forces]]\non = "m1"\nf = "F0*cos(W*t)"\n', {"f.csv": FORCE_TABLE}, "masses"),
    "table-force-jumps": ('[[forces]]\non = "m3"\ntable = "j.csv"\n', {"j.csv": JUMP_TABLE}, "masses"),
    "ground-expression": ('[[dampers]]\nbetween = ["m1", "wall"]\nc = "c"\n[ground]\n'
                          'acceleration = "A*sin(W*t) + 0.1*cos(2*t)"\n', {}, "masses"),
    "ground-table": ('[ground]\ntable = "g.csv"\n', {"g.csv": GROUND_TABLE}, "masses"),
    "chain-loads": ('[[forces]]\non = 6\nf = "F0*cos(1.7*t)"\n[[forces]]\non = 2\ntable = "f.csv"\n'
                    '[ground]\ntable = "g.csv"\n', {"f.csv": FORCE_TABLE, "g.csv": GROUND_TABLE}, "chain"),
    "chain-ground-expression": ('[ground]\nacceleration = "A*cos(2*t)"\n', {}, "chain"),
    "chain-gravity": ('[gravity]\ng = "0.5*A"\n[[forces]]\non = 3\nf = "F0*sin(t)"\n', {}, "chain"),
}


def _case(tmp_path, name):
    extra, tables, kind = CASES[name]
    make = masses_scene if kind == "masses" else chain_scene
    return make(tmp_path, extra, tables, name=name.replace("-", "_"))


@pytest.mark.parametrize("name", list(CASES))
def test_exact_matches_dop853_reference(tmp_path, name):
    path = _case(tmp_path, name)
    scene, system = scene_and_system(path)
    assert system.exact_available
    runs = run_methods(system, scene.x0, scene.v0, scene.dt, scene.steps, ["modal"])
    rhs, n, knots, *_ = reference(path)
    xr, vr = dop853_piecewise(rhs, n, scene.x0, scene.v0, runs["modal"].t, knots)
    assert np.max(np.abs(runs["modal"].x - xr)) <= 1e-8 * np.max(np.abs(xr))
    assert np.max(np.abs(runs["modal"].v - vr)) <= 1e-8 * np.max(np.abs(vr))


@pytest.mark.parametrize("name", ["table-force-damped", "table-force-jumps", "ground-table", "chain-loads"])
def test_exact_last_frame_off_the_recording_stride_with_tables(tmp_path, name):
    """Steps not a multiple of record_every: the last frame (t = steps·h, a shorter last interval) is the
    state there, not the initial state (oracle finding N5: the tables' first-order hold restarted at it)."""
    path = _case(tmp_path, name)
    scene, system = scene_and_system(path)
    steps, every = 400, 7  # 400 = 57·7 + 1
    run = run_methods(system, scene.x0, scene.v0, scene.dt, steps, ["modal"], record_every=every)["modal"]
    assert abs(run.t[-1] - steps * scene.dt) <= 1e-12 * steps * scene.dt and run.t[-1] - run.t[-2] < every * scene.dt
    rhs, n, knots, *_ = reference(path)
    xr, vr = dop853_piecewise(rhs, n, scene.x0, scene.v0, run.t, knots)
    assert np.max(np.abs(run.x - xr)) <= 1e-8 * np.max(np.abs(xr))
    assert np.max(np.abs(run.v - vr)) <= 1e-8 * np.max(np.abs(vr))


@pytest.mark.parametrize("name", ["table-force-damped", "ground-expression", "ground-table", "chain-loads",
                                  "chain-gravity"])
def test_verlet_is_second_order_against_reference(tmp_path, name):
    path = _case(tmp_path, name)
    scene, system = scene_and_system(path)
    rhs, n, knots, *_ = reference(path)
    T = 4.0
    hs = [0.02, 0.01, 0.005]
    errs = []
    for h in hs:
        run = run_methods(system, scene.x0, scene.v0, h, int(round(T / h)), ["verlet"])["verlet"]
        xr, _ = dop853_piecewise(rhs, n, scene.x0, scene.v0, run.t, knots)
        errs.append(np.max(np.abs(run.x - xr)))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 2.0) < 0.15, (errs, slope)


# -- NPZ: absolute motion -----------------------------------------------------------------------------
def test_npz_has_absolute_motion_only_with_ground(tmp_path):
    path = _case(tmp_path, "ground-expression")
    run = sc.simulate(str(path), steps=200, out=tmp_path / "out", progress=False)
    data = np.load(tmp_path / "out" / "ground_expression.npz")
    assert {"aabs_modal", "xabs_modal", "aabs_verlet", "xabs_verlet"} <= set(data.files)
    _, _, _, a_g, x_g, absolute = reference(path)
    t = data["t"]
    xabs_ref = data["x_modal"] + x_g(t)[:, None]
    assert np.max(np.abs(data["xabs_modal"] - xabs_ref)) <= 1e-12 * np.max(np.abs(xabs_ref))
    aref = np.array([absolute(s, x, v) for s, x, v in zip(t, data["x_modal"], data["v_modal"])])
    assert np.max(np.abs(data["aabs_modal"] - aref)) <= 1e-10 * np.max(np.abs(aref))
    assert set(run.extra) == {"aabs_modal", "xabs_modal", "aabs_verlet", "xabs_verlet"}

    table = sc.simulate(str(_case(tmp_path, "ground-table")), steps=100, out=tmp_path / "out2", progress=False)
    files = set(np.load(table.npz).files)
    assert {"aabs_modal", "aabs_verlet"} <= files and not any(f.startswith("xabs") for f in files)
    plain = sc.simulate(str(_case(tmp_path, "table-force-damped")), steps=50, out=tmp_path / "out3",
                        progress=False)
    assert not any(f.startswith(("aabs", "xabs")) for f in np.load(plain.npz).files)


def test_chain_with_ground_streams_absolute_acceleration(tmp_path):
    run = sc.simulate(str(_case(tmp_path, "chain-ground-expression")), steps=100, out=tmp_path / "o",
                      progress=False)
    files = set(np.load(run.npz).files)
    assert {"aabs_modal", "xabs_modal", "aabs_verlet", "xabs_verlet"} <= files


# -- hostile input ------------------------------------------------------------------------------------
HOSTILE = [
    ("missing.csv", None, "cannot read the file (No such file or directory"),
    ("t,f\n0,1\n2,3\n1,0\n", None, "not strictly increasing at row 3"),
    ("t,f\n0,1\n0,2\n", None, "not strictly increasing"),
    ("t,f\n0,1\nnan,2\n", None, "not a finite number"),
    ("t,f\n0,1\n1,inf\n", None, "not a finite number"),
    ("t,f\n0,1\n1,1e400\n", None, "not a finite number"),
    ("time,force\n0,1\n1,2\n", None, "header"),
    ("t,a\n0,1\n1,2\n", None, "header"),
    ("t,f,g\n0,1,2\n1,2,3\n", None, "header"),
    ("t,f\n0,1,2\n1,2\n", None, "3 columns"),
    ("t,f\n0,one\n1,2\n", None, "is not a number"),
    ("", None, "empty"),
    ("t,f\n0,1\n", None, "1 data rows"),
    (b"t,f\n0,\xff\n", None, "not UTF-8"),
]


@pytest.mark.parametrize("body, _unused, why", HOSTILE)
def test_hostile_force_tables_are_refused_in_one_line(tmp_path, body, _unused, why):
    tables = {} if body == "missing.csv" else {"bad.csv": body}
    if isinstance(body, bytes):
        (tmp_path / "bad.csv").write_bytes(body)
        tables = {}
    fname = "missing.csv" if body == "missing.csv" else "bad.csv"
    path = masses_scene(tmp_path, f'[[forces]]\non = "m1"\ntable = "{fname}"\n', tables)
    with pytest.raises(SceneError) as err:
        load_scene(path)
    msg = str(err.value)
    assert "\n" not in msg and str(path) in msg and "forces[0].table" in msg and why in msg
    assert "accepted: a CSV file with a header line 't,f'" in msg


@pytest.mark.parametrize("name", ["/etc/passwd", "../outside.csv", "link.csv", "sub/../../outside.csv"])
def test_tables_outside_the_scene_folder_are_refused(tmp_path, name):
    (tmp_path / "outside.csv").write_text(FORCE_TABLE)
    scene_dir = tmp_path / "scene"
    scene_dir.mkdir()
    (scene_dir / "sub").mkdir()
    (scene_dir / "link.csv").symlink_to(tmp_path / "outside.csv")
    path = masses_scene(scene_dir, f'[[forces]]\non = "m1"\ntable = "{name}"\n')
    with pytest.raises(SceneError, match="outside the scene file's folder"):
        load_scene(path)
    (scene_dir / "sub" / "inside.csv").write_text(FORCE_TABLE)
    load_scene(masses_scene(scene_dir, '[[forces]]\non = "m1"\ntable = "sub/inside.csv"\n'))


@pytest.mark.parametrize("extra, key, why", [
    ('[[forces]]\non = "m1"\nf = "t"\ntable = "f.csv"\n', "forces[0]", "exactly one of f and table"),
    ('[[forces]]\non = "m1"\n', "forces[0]", "exactly one of f and table"),
    ('[ground]\nacceleration = "t"\ntable = "g.csv"\n', "ground", "exactly one of acceleration and table"),
    ('[ground]\n', "ground", "exactly one of acceleration and table"),
    ('[ground]\naccel = "t"\n', "ground.accel", "unknown key"),
    ('[ground]\nacceleration = "__import__(1)"\n', "ground.acceleration", ""),
    ('[ground]\ntable = "f.csv"\n', "ground.table", "header"),
    ('[[forces]]\non = 0\nf = "t"\n', "forces[0].on", "not a mass"),
])
def test_hostile_load_entries(tmp_path, extra, key, why):
    path = masses_scene(tmp_path, extra, {"f.csv": FORCE_TABLE, "g.csv": GROUND_TABLE})
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert f": {key}: " in str(err.value) and why in str(err.value) and "accepted" in str(err.value)


@pytest.mark.parametrize("on", ["7", "-1", "true", '"m1"', "2.0"])
def test_chain_force_names_a_mass_by_index(tmp_path, on):
    path = chain_scene(tmp_path, f'[[forces]]\non = {on}\nf = "F0"\n')
    with pytest.raises(SceneError, match=r"forces\[0\]\.on: .*accepted: a whole number 0 \.\.\. 6"):
        load_scene(path)


def test_cli_refuses_a_bad_table_in_one_line_with_exit_2(tmp_path, capsys):
    path = masses_scene(tmp_path, '[[forces]]\non = "m1"\ntable = "bad.csv"\n', {"bad.csv": "t,f\n1,0\n0,1\n"})
    assert main(["simulate", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "forces[0].table" in err and "bad.csv" in err


def test_bundled_building_quake_exact_matches_reference():
    """The README's building under its (synthetic) record: exact vs DOP853 over the first 4 s."""
    path = ROOT / "scenes" / "building_quake.toml"
    scene, system = scene_and_system(path)
    runs = run_methods(system, scene.x0, scene.v0, scene.dt, 800, ["modal"])
    rhs, n, knots, *_ = reference(path)
    xr, vr = dop853_piecewise(rhs, n, scene.x0, scene.v0, runs["modal"].t, knots)
    assert np.max(np.abs(runs["modal"].x - xr)) <= 1e-8 * np.max(np.abs(xr))
    assert np.max(np.abs(runs["modal"].v - vr)) <= 1e-8 * np.max(np.abs(vr))


def test_non_harmonic_ground_expression_runs_verlet_at_order_2_and_refuses_exact(tmp_path):
    path = masses_scene(tmp_path, '[ground]\nacceleration = "A*exp(-t)*sin(W*t)"\n', name="decay")
    scene, system = scene_and_system(path)
    assert not system.exact_available
    with pytest.raises(sc.RunRefused, match="not constant \\+ harmonic"):
        run_methods(system, scene.x0, scene.v0, scene.dt, 10, ["modal"])
    rhs, n, knots, *_ = reference(path)
    hs, errs = [0.02, 0.01, 0.005], []
    for h in hs:
        run = run_methods(system, scene.x0, scene.v0, h, int(round(4.0 / h)), ["verlet"])["verlet"]
        xr, _ = dop853_piecewise(rhs, n, scene.x0, scene.v0, run.t, knots)
        errs.append(np.max(np.abs(run.x - xr)))
    assert abs(np.polyfit(np.log(hs), np.log(errs), 1)[0] - 2.0) < 0.15, errs
    sim = sc.simulate(str(path), steps=50, progress=False)
    assert sim.methods == ["verlet"] and {"aabs_verlet", "xabs_verlet"} == set(sim.extra)


def test_long_loaded_chain_needs_no_n_by_n_memory(tmp_path):
    """A loaded chain of 40 000 masses (an n x n float array would take 12.8 GB) runs Verlet
    through the forcing splitting in memory proportional to n."""
    import tracemalloc

    text = chain_text("longload", '[[forces]]\non = 39999\ntable = "f.csv"\n'
                      '[[forces]]\non = 0\nf = "F0*sin(0.3*t)"\n[ground]\nacceleration = "A*cos(0.5*t)"\n', n=40000)
    path = write(tmp_path, text, {"f.csv": FORCE_TABLE}, "longload")
    scene, system = scene_and_system(path)
    assert not system.exact_available
    tracemalloc.start()
    run = run_methods(system, scene.x0, scene.v0, 0.05, 40, ["verlet"], record_every=20)["verlet"]
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.all(np.isfinite(run.x)) and peak < 200 * 40000 * 8, peak


def test_system_needs_the_scene_tables():
    module, _ = load_module(load_scene(ROOT / "scenes" / "building_quake.toml"))
    with pytest.raises(ValueError, match="ground table"):
        System.from_module(module)


# -- first-order hold: any piecewise-linear table, one damped oscillator -----------------------------
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

ONE = """
name = "one"
[parameters]
m = 1.3
k = 2.0
c = 0.1
[masses]
m1 = "m"
[[springs]]
between = ["wall", "m1"]
k = "k"
[[dampers]]
between = ["wall", "m1"]
c = "c"
[[forces]]
on = "m1"
table = "r.csv"
[initial]
x = [0.1]
v = [0.0]
[simulation]
dt = 0.05
steps = 80
"""


@settings(max_examples=15)
@given(gaps=st.lists(st.floats(0.05, 1.5), min_size=1, max_size=6),
       values=st.lists(st.floats(-2.0, 2.0), min_size=7, max_size=7),
       start=st.floats(-0.5, 2.0))
def test_first_order_hold_is_exact_for_any_piecewise_linear_table(tmp_path_factory, gaps, values, start):
    tmp = tmp_path_factory.mktemp("foh")
    times = start + np.concatenate([[0.0], np.cumsum(gaps)])
    rows = "\n".join(f"{float(t)!r},{float(v)!r}" for t, v in zip(times, values))
    path = write(tmp, ONE, {"r.csv": "t,f\n" + rows + "\n"}, "one")
    scene, system = scene_and_system(path)
    run = run_methods(system, scene.x0, scene.v0, scene.dt, scene.steps, ["modal"])["modal"]
    rhs, n, knots, *_ = reference(path)
    xr, vr = dop853_piecewise(rhs, n, scene.x0, scene.v0, run.t, knots)
    assert np.max(np.abs(run.x - xr)) <= 1e-8 * np.max(np.abs(xr))
    assert np.max(np.abs(run.v - vr)) <= 1e-8 * np.max(np.abs(vr))
