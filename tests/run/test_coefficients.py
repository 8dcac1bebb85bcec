"""Coefficient tables (numeric.integrators.coefficients and the method modules) check themselves.

Identities to 1e-14: weights sum to one, palindromes, power sums of the
compositions, the published Blanes–Moan numbers and their derived middle
coefficients; tables that break an identity raise ValueError naming the
table; the linear stability limits computed from the tables separate bounded
from growing powers of the one-step map; the Chebyshev propagator's Bessel
series reproduce cos(h√λ), sin(h√λ)/√λ and −√λ sin(h√λ) on the whole interval.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from springchain.numeric.integrators import LinearChain
from springchain.numeric.run import registry
from springchain.numeric.run.protocol import Kind
from springchain.numeric.integrators.blanes_moan4 import BLANES_MOAN4
from springchain.numeric.integrators.blanes_moan6 import BLANES_MOAN6
from springchain.numeric.integrators.chebyshev import ChebyshevCoefficients
from springchain.numeric.integrators.coefficients import CompositionTable, SplittingTable
from springchain.numeric.integrators.kahan_li import KAHAN_LI8
from springchain.numeric.integrators.splitting import SplittingMethod
from springchain.numeric.integrators.yoshida import YOSHIDA4

INTEGRATORS = registry.classes(Kind.STEP)
SPLITTING = {name: cls for name, cls in INTEGRATORS.items() if issubclass(cls, SplittingMethod)}
COMPOSITIONS = [YOSHIDA4, KAHAN_LI8]


def test_every_composition_and_splitting_method_is_registered():
    assert set(SPLITTING) == {"yoshida4", "blanes-moan4", "blanes-moan6", "kahan-li8"}


@pytest.mark.parametrize("name", sorted(SPLITTING))
def test_splitting_tables_weights_sum_to_one_and_are_palindromic(name):
    cls = SPLITTING[name]
    t = cls.table
    assert len(t.kicks) == len(t.drifts) + 1
    assert abs(math.fsum(t.kicks) - 1.0) < 1e-14
    assert abs(math.fsum(t.drifts) - 1.0) < 1e-14
    assert np.max(np.abs(np.subtract(t.kicks, t.kicks[::-1]))) < 1e-14
    assert np.max(np.abs(np.subtract(t.drifts, t.drifts[::-1]))) < 1e-14
    # declared properties follow from the table
    assert cls.order == t.order and cls.evals_per_step == len(t.drifts) and cls.symplectic
    assert abs(t.nodes[-1] - 1.0) < 1e-14


def test_declared_stage_counts():
    assert [SPLITTING[n].evals_per_step for n in ("yoshida4", "blanes-moan4", "blanes-moan6", "kahan-li8")] \
        == [3.0, 6.0, 11.0, 17.0]


@pytest.mark.parametrize("table", COMPOSITIONS, ids=lambda t: t.name)
def test_composition_power_sums_vanish(table):
    """Σγ = 1 and Σγ^q = 0 for odd q < order; Σγ^order is not zero (the order is not higher by accident)."""
    assert abs(table.power_sum(1) - 1.0) < 1e-14
    for q in range(3, table.order, 2):
        assert abs(table.power_sum(q)) < 1e-14, q
    assert abs(table.power_sum(table.order + 1)) > 1e-6


def test_yoshida_weights_closed_form():
    g1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
    assert np.allclose(YOSHIDA4.weights, [g1, -(2.0 ** (1.0 / 3.0)) * g1, g1], rtol=0, atol=1e-14)


def test_composition_as_splitting_merges_neighbouring_half_kicks():
    s = KAHAN_LI8.splitting()
    w = KAHAN_LI8.weights
    assert len(w) == 17 and s.drifts == w
    assert abs(s.kicks[0] - w[0] / 2) < 1e-16 and abs(s.kicks[-1] - w[-1] / 2) < 1e-16
    assert all(abs(s.kicks[j] - (w[j - 1] + w[j]) / 2) < 1e-16 for j in range(1, 17))


def test_blanes_moan_tables_are_the_published_numbers():
    """J. Comput. Appl. Math. 142 (2002) Table 3: SRKN_6^b and SRKN_11^b (b-type: the sequence starts with a kick)."""
    t4 = BLANES_MOAN4
    assert t4.kicks[:3] == (0.0829844064174052, 0.396309801498368, -0.0390563049223486)
    assert t4.drifts[:2] == (0.245298957184271, 0.604872665711080)
    assert abs(t4.drifts[2] - (0.5 - 0.245298957184271 - 0.604872665711080)) < 1e-15
    assert abs(t4.kicks[3] - 0.1195241940131508) < 1e-14  # middle kick as tabulated by Principia
    t6 = BLANES_MOAN6
    assert t6.kicks[:5] == (0.0414649985182624, 0.198128671918067, -0.0400061921041533,
                            0.0752539843015807, -0.0115113874206879)
    assert t6.drifts[:5] == (0.123229775946271, 0.290553797799558, -0.127049212625417,
                             -0.246331761062075, 0.357208872795928)
    assert abs(t6.drifts[5] - 0.2047770542914700) < 1e-14
    assert abs(t6.kicks[5] - 0.2366699247869311) < 1e-14 and t6.kicks[5] == t6.kicks[6]
    assert (t4.stages, t6.stages) == (6, 11)


# --- tables that break an identity are refused, naming the table --------------------------------

@pytest.mark.parametrize("kwargs, message", [
    (dict(kicks=(0.5, 0.6), drifts=(1.0,), order=2), "kick"),
    (dict(kicks=(0.5, 0.5), drifts=(0.9,), order=2), "drift"),
    (dict(kicks=(0.5, 0.5), drifts=(0.5, 0.5), order=2), "m \\+ 1 kicks"),
    (dict(kicks=(0.25, 0.25, 0.5), drifts=(0.5, 0.5), order=2), "palindromic"),
    (dict(kicks=(0.5, 0.5), drifts=(1.0,), order=3), "even order"),
    (dict(kicks=(0.5, math.nan), drifts=(1.0,), order=2), "finite"),
])
def test_bad_splitting_table_raises_naming_the_table(kwargs, message):
    with pytest.raises(ValueError, match=f"'broken'.*{message}"):
        SplittingTable("broken", **kwargs)


@pytest.mark.parametrize("weights, order, message", [
    ((0.5, 0.6), 2, "sum"),
    ((0.3, 0.4, 0.3), 4, "w\\*\\*3"),
    ((0.2, 0.8), 2, "palindromic"),
    ((1.0,), 3, "even"),
])
def test_bad_composition_table_raises_naming_the_table(weights, order, message):
    with pytest.raises(ValueError, match=f"'broken'.*{message}"):
        CompositionTable("broken", weights, order)


def test_dropping_a_digit_breaks_the_kahan_li_table():
    w = list(KAHAN_LI8.weights)
    w[3] = round(w[3], 8)
    w[-4] = w[3]
    w[8] = 1.0 - 2.0 * math.fsum(w[:8])
    with pytest.raises(ValueError, match="kahan-li8-truncated.*w\\*\\*3"):
        CompositionTable("kahan-li8-truncated", w, 8)


def test_linear_chain_shapes_are_checked():
    with pytest.raises(ValueError, match="LinearChain"):
        LinearChain(np.ones(3), np.array([[0, 1]]), np.ones(2))
    with pytest.raises(ValueError, match="LinearChain.*positive"):
        LinearChain(np.array([1.0, -1.0]), np.array([[0, 1]]), np.ones(1))
    with pytest.raises(ValueError, match="LinearChain.*indices"):
        LinearChain(np.ones(2), np.array([[0, 2]]), np.ones(1))


# --- linear stability limits computed from the tables ---------------------------------------------

def test_verlet_as_a_table_has_the_textbook_stability_limit():
    assert abs(CompositionTable("verlet", (1.0,), 2).splitting().stability_limit - 2.0) < 1e-9


@pytest.mark.parametrize("name", sorted(SPLITTING))
def test_stability_limit_separates_bounded_from_growing(name):
    """Spectral radius of the harmonic-oscillator map is 1 on (0, z*) and > 1 just above z*.

    (Blanes–Moan 4 and 6 lose stability in a narrow gap just above ωh = π and are
    stable again beyond it: the limit is the first instability, not the last.)
    """
    t = SPLITTING[name].table
    z = t.stability_limit

    def rho(q):
        return float(np.max(np.abs(np.linalg.eigvals(t.propagator(q)))))

    assert 1.0 < z < 2.0 * len(t.drifts)
    assert max(rho(q) for q in np.linspace(1e-3, z * (1 - 1e-9), 400)) < 1.0 + 1e-12
    assert rho(z + 1e-5) > 1.0 + 1e-5


def test_yoshida_stability_limit_is_below_verlets():
    """The triple jump's negative middle step shrinks the stable step (≈ 1.5734 vs 2)."""
    assert abs(SPLITTING["yoshida4"].stability_limit - 1.5734) < 1e-3


# --- Chebyshev series with Bessel coefficients ----------------------------------------------------

def _functions(lam, h):
    s = np.sqrt(lam)
    return np.cos(h * s), h * np.sinc(h * s / np.pi), -s * np.sin(h * s)


def _check_series(h, r2):
    co = ChebyshevCoefficients.from_bessel(h, r2)
    lam = np.linspace(0.0, r2, 257)
    T = np.polynomial.chebyshev.chebvander(2 * lam / r2 - 1, co.degree)
    c, g, w = _functions(lam, h)
    R = math.sqrt(r2)
    k = co.degree + 1
    assert np.max(np.abs(T @ co.cos - c)) < 1e-14 * k
    assert np.max(np.abs(T @ co.sinc - g)) < 1e-14 * k * h
    assert np.max(np.abs(T @ co.wsin - w)) < 1e-14 * k * R
    return co


@pytest.mark.parametrize("h, r2", [(0.1, 10 / 3), (1.0, 4.0), (7.5, 4.0), (40.0, 4.0), (0.01, 1e6)])
def test_bessel_series_reproduce_the_exact_step_functions(h, r2):
    co = _check_series(h, r2)
    # about hR/2 terms, plus a margin that grows slowly
    z = h * math.sqrt(r2)
    assert z / 2 - 1 <= co.degree <= z / 2 + 4 * z ** (1 / 3) + 12


@given(h=st.floats(1e-3, 30.0), r2=st.floats(1e-2, 1e3))
def test_bessel_series_any_step(h, r2):
    _check_series(h, r2)


def test_bessel_series_match_chebyshev_interpolation():
    """The Bessel route and plain interpolation at Chebyshev points give the same coefficients."""
    h, r2 = 3.0, 5.0
    co = ChebyshevCoefficients.from_bessel(h, r2)
    for coef, fn in zip((co.cos, co.sinc, co.wsin), range(3)):
        interp = np.polynomial.chebyshev.chebinterpolate(
            lambda y, fn=fn: _functions(r2 * (1 + y) / 2, h)[fn], co.degree + 8)
        assert np.max(np.abs(interp[: co.degree + 1] - coef)) < 1e-14 * max(1.0, h, math.sqrt(r2))


def test_chebyshev_coefficients_check_themselves():
    co = ChebyshevCoefficients.from_bessel(2.0, 3.0)
    bad = co.cos.copy()
    bad[3] += 1e-9
    with pytest.raises(ValueError, match="Chebyshev coefficients.*cos"):
        ChebyshevCoefficients(co.h, co.radius2, bad, co.sinc, co.wsin)
    with pytest.raises(ValueError, match="same length"):
        ChebyshevCoefficients(co.h, co.radius2, co.cos[:-1], co.sinc, co.wsin)


@pytest.mark.parametrize("name", sorted(SPLITTING))
def test_half_traces_are_the_propagators_half_traces(name):
    """The scan of the stability limit evaluates trace(P(z))/2 on whole grids; it is the 2x2 map's."""
    t = SPLITTING[name].table
    z = np.random.default_rng(7).uniform(0.0, 2.0 * len(t.drifts), 50)
    want = np.array([0.5 * np.trace(t.propagator(q)) for q in z])
    np.testing.assert_allclose(t.half_traces(z), want, rtol=1e-12, atol=1e-12)
