"""Data out (pandas, xarray) and notebook display (issue 23, items 2 and 3)."""

from __future__ import annotations

import base64
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import springchain as sc

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def building_run():
    return sc.simulate("building", steps=120, progress=False)


def test_simulation_to_xarray(building_run):
    run = building_run
    ds = run.to_xarray()
    assert dict(ds.sizes) == {"time": len(run.t), "mass": 3}
    assert list(ds["mass"].values) == ["floor1", "floor2", "floor3"]
    np.testing.assert_array_equal(ds["time"].values, run.t)
    assert set(ds.data_vars) == {"x_modal", "x_verlet", "v_modal", "v_verlet"}
    for m in ("modal", "verlet"):
        np.testing.assert_array_equal(ds[f"x_{m}"].values, run.x[m])
        np.testing.assert_array_equal(ds[f"v_{m}"].values, run.v[m])
        assert ds[f"x_{m}"].dims == ("time", "mass")
    assert ds["x_modal"].attrs["units"] == "m" and ds["v_verlet"].attrs["units"] == "m/s"
    assert ds.attrs["scene"] == "building" and ds.attrs["dt"] == pytest.approx(0.005)
    assert "x: m" in ds.attrs["units"] and ds["time"].attrs["units"] == "s"
    # selection by name works as a user expects
    np.testing.assert_array_equal(ds["x_verlet"].sel(mass="floor3").values, run.x["verlet"][:, 2])


def test_simulation_to_dataframe_is_long(building_run):
    run = building_run
    df = run.to_dataframe()
    assert list(df.columns) == ["method", "quantity", "time", "mass", "value", "unit"]
    assert len(df) == 2 * 2 * len(run.t) * 3
    wide = df[(df.method == "verlet") & (df.quantity == "v")].pivot(index="time", columns="mass", values="value")
    np.testing.assert_array_equal(wide[["floor1", "floor2", "floor3"]].to_numpy(), run.v["verlet"])
    assert set(df.loc[df.quantity == "x", "unit"]) == {"m"}


def test_ground_scenes_carry_absolute_motion_and_chains_index_coordinates(tmp_path):
    run = sc.simulate("building_quake", ["modal"], steps=50, progress=False)
    ds = run.to_xarray()
    assert "aabs_modal" in ds and ds["aabs_modal"].attrs["units"] == "m/s^2"
    chain = sc.load("chain100k").with_parameters()  # a [chain]: masses are indices
    text = 'name = "c8"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 8\nmass = "m"\nk = "k"\n[initial]\nx = "0.01*i"\n'
    (tmp_path / "c8.toml").write_text(text)
    crun = sc.simulate(tmp_path / "c8.toml", ["verlet"], steps=10, out=tmp_path / "o", progress=False)
    cds = crun.to_xarray()
    assert list(cds["mass"].values) == list(range(8)) and chain.n == 100_000


def test_frf_modes_and_sweep_tables(tmp_path):
    h = sc.frf("building", "floor3", "floor3", points=60, transfer=False)
    df = h.to_dataframe()
    np.testing.assert_array_equal(df["omega"].to_numpy(), h.omega)
    np.testing.assert_array_equal(df["H"].to_numpy(), h.H)
    np.testing.assert_allclose(df["magnitude"].to_numpy(), np.abs(h.H))
    m = sc.modes("seed")
    mdf = m.to_dataframe()
    np.testing.assert_array_equal(mdf["omega2_value"].to_numpy(), m.omega2_values)
    assert list(mdf["omega2"]) == ["0", "k/m", "5*k/(3*m)"]
    np.testing.assert_allclose(mdf[["shape_m1", "shape_m2", "shape_m3"]].to_numpy()[2], [1.0, -2 / 3, 1.0])
    r = sc.sweep("seed", vary=["k=grid(1, 2, 3)"], samples=2, workers=1, out=tmp_path / "s", progress=False)
    pdf = r.to_pandas()
    assert list(pdf["sample"]) == list(range(6))
    np.testing.assert_allclose(np.stack(pdf["omega2"].to_numpy())[:, 1], pdf["k"].to_numpy(), rtol=1e-14)


def test_missing_extra_is_one_line_naming_it(building_run, monkeypatch):
    monkeypatch.setitem(sys.modules, "xarray", None)
    monkeypatch.setitem(sys.modules, "pandas", None)
    for call in (building_run.to_xarray, building_run.to_dataframe):
        with pytest.raises(ImportError) as exc:
            call()
        assert str(exc.value).count("\n") == 0 and 'pip install "springchain[data]"' in str(exc.value)


# -- display -------------------------------------------------------------------------------------------
def _images(text: str, mime: str) -> list[bytes]:
    return [base64.b64decode(b) for b in re.findall(rf'src="data:{mime};base64,([A-Za-z0-9+/=]+)"', text)]


def test_rich_display_of_every_result(building_run, tmp_path):
    run = building_run
    page = run._repr_html_()
    assert "<table" in page and "max |x − x_exact|" in page and "verlet" in page
    (png,) = _images(page, "image/png")
    assert png.startswith(PNG) and run._repr_png_().startswith(PNG)
    h = sc.frf("building", "floor3", "floor3", points=60, transfer=False)
    page = h._repr_html_()
    assert "ω_n [rad/s]" in page and _images(page, "image/png")[0].startswith(PNG)
    assert page.count("<tr>") == 1 + 3  # header + three resonances
    a = sc.animate("seed", frames=3, out=tmp_path)
    (gif,) = _images(a._repr_html_(), "image/gif")
    assert gif.startswith(b"GIF89a") and gif == a.path.read_bytes()
    p = sc.plan("seed", 1e-3, t_end=10.0)
    page = p._repr_html_()
    assert f"recommended: {p.recommended.name}" in page and '<tr style="font-weight:bold"><td' in page
    r = sc.sweep("seed", vary=["k=uniform(1, 2)"], samples=4, workers=1, out=tmp_path / "s", progress=False)
    page = r._repr_html_()
    assert "ω² mean" in page and page.count("<tr>") == 1 + 3


def test_display_uses_no_pyplot_and_warns_nothing(tmp_path):
    code = textwrap.dedent("""
        import sys, warnings
        warnings.simplefilter("error")
        import matplotlib
        before = matplotlib.get_backend()
        import springchain as sc
        run = sc.simulate("seed", steps=50, progress=False)
        run._repr_html_(); run._repr_png_()
        sc.frf("seed", "m1", "m3", points=40, transfer=False)._repr_html_()
        crun = sc.simulate("chain100k", ["verlet"], steps=4, out=sys.argv[1], progress=False)
        crun._repr_html_()
        assert "matplotlib.pyplot" not in sys.modules
        assert matplotlib.get_backend() == before
        print("ok")
    """)
    res = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr


def test_mimebundle_draws_the_figure_once(building_run, monkeypatch):
    from springchain import _display

    calls = []
    real = _display.simulation_png
    monkeypatch.setattr(_display, "simulation_png", lambda sim: calls.append(1) or real(sim))
    bundle = building_run._repr_mimebundle_()
    assert len(calls) == 1 and set(bundle) == {"text/html", "image/png", "text/plain"}
    assert _images(bundle["text/html"], "image/png")[0] == bundle["image/png"]
