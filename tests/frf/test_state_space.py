"""State-space models (issue 37, item 2): SciPy's ``freqresp`` and python-control's frequency response
of ``sc.state_space`` against ``sc.frf`` (the accurate route, itself tested against mpmath), the
sparse ``[chain]`` form, the one-line note at wide contrast, and refusals.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.signal as sg
import scipy.sparse
from helpers import chain_toml, write_scene

import springchain as sc

MASSES = ("floor1", "floor2", "floor3")
FACTOR = {"x": lambda w: 1.0, "v": lambda w: 1j * w, "a": lambda w: -w * w}


@pytest.mark.parametrize("kind", ["x", "v", "a"])
def test_scipy_freqresp_equals_frf_at_mild_contrast(kind):
    """Every input and output of the three-storey building, over frf's whole refined grid."""
    worst = 0.0
    for i in MASSES:
        for o in MASSES:
            h = sc.frf("building", i, o, transfer=False)
            ss = sc.state_space("building", i, f"{o}:{kind}")
            assert isinstance(ss, sg.StateSpace) and ss.A.shape == (6, 6)
            w, H = sg.freqresp(ss, h.omega)
            ref = h.H * FACTOR[kind](h.omega)
            worst = max(worst, float(np.max(np.abs(H - ref) / np.abs(ref))))
    assert worst < 1e-12, worst


def test_python_control_model_is_named_and_its_response_equals_frf():
    control = pytest.importorskip("control")
    cs = sc.state_space("building", ["floor1", "floor3"], ["floor3", "floor3:a"], form="control")
    assert isinstance(cs, control.StateSpace)
    assert cs.input_labels == ["F_floor1", "F_floor3"] and cs.output_labels == ["x_floor3", "a_floor3"]
    assert cs.state_labels[:3] == ["x_floor1", "x_floor2", "x_floor3"]
    h = sc.frf("building", "floor1", "floor3", transfer=False)
    resp = control.frequency_response(cs, h.omega)
    H = np.asarray(resp.complex)  # (outputs, inputs, W)
    assert np.max(np.abs(H[0, 0] - h.H) / np.abs(h.H)) < 1e-11
    assert np.max(np.abs(H[1, 0] + h.omega**2 * h.H) / np.abs(h.omega**2 * h.H)) < 1e-11


def test_ground_input_relative_displacement_and_absolute_acceleration():
    """Under a base acceleration a_g: x_rel / a_g = −Σ_k m_k H(out, k) and a_abs / a_g = 1 − ω² x_rel / a_g,
    formed from frf's receptances (three solves) on a band around the resonances."""
    m = sc.load("building").parameters["m"]
    h = [sc.frf("building", k, "floor3", transfer=False, omega_min=2.0, omega_max=60.0, points=60) for k in MASSES]
    w = h[0].omega
    from springchain.numeric.frf.response import operator, receptance

    Hk = [receptance(operator(_system()), w, j, 2) for j in range(3)]
    rel = -m * sum(Hk)
    model = sc.state_space("building", "ground", ["floor3", "floor3:a"], form="matrices")
    H = model.freqresp(w)
    assert np.max(np.abs(H[0, 0] - rel) / np.abs(rel)) < 1e-11
    absolute = 1 - w**2 * rel
    assert np.max(np.abs(H[1, 0] - absolute) / np.abs(absolute)) < 1e-10


def _system():
    from springchain._modules import system_of

    return system_of(sc.load("building"))[0]


def test_a_chain_is_sparse_and_its_response_equals_frf(tmp_path):
    path = write_scene(tmp_path, "ch", chain_toml(300, "wall", "free", extra='[damping]\nrayleigh = [0.02, 0.001]\n'))
    model = sc.state_space(path, "5", ["299", "299:v"])
    assert scipy.sparse.issparse(model.A) and model.A.shape == (600, 600) and model.A.nnz < 6 * 600
    h = sc.frf(path, 5, 299, omega_min=0.05, omega_max=3.0, points=25)
    H = model.freqresp(h.omega)
    assert np.max(np.abs(H[0, 0] - h.H) / np.abs(h.H)) < 1e-9
    assert np.max(np.abs(H[1, 0] - 1j * h.omega * h.H) / np.abs(h.omega * h.H)) < 1e-9


def test_wide_contrast_gets_a_one_line_note(tmp_path):
    path = write_scene(tmp_path, "wide", '''name = "wide"
[parameters]
[masses]
a = 1.0
b = 1.0
[[springs]]
between = ["wall", "a"]
k = 1e9
[[springs]]
between = ["a", "b"]
k = 1e-3
[[dampers]]
between = ["wall", "b"]
c = 0.01
''')
    with pytest.warns(sc.AccuracyWarning, match="element contrast 1e.12") as rec:
        sc.state_space(path, "a", "b")
    assert len(rec) == 1 and "\n" not in str(rec[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc.state_space("building", "floor1", "floor3")  # mild: no note


@pytest.mark.parametrize("inputs, outputs, form, match", [
    ("floor9", "floor1", "scipy", "not a mass"),
    ("floor1", "floor1:jerk", "scipy", "kind 'jerk'"),
    ("floor1", "floor1", "octave", "form 'octave'"),
    ([], "floor1", "scipy", "none given"),
])
def test_bad_requests_are_refused_in_one_line(inputs, outputs, form, match):
    with pytest.raises(sc.RunRefused, match=match) as info:
        sc.state_space("building", inputs, outputs, form=form)
    assert "\n" not in str(info.value)
