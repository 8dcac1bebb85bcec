"""ω² of index-dependent ``[chain]`` modules (no closed form) against a 60-digit mpmath reference.

The generated ``omega2()`` takes the singular values of the bidiagonal spring factor by bisection
on its Golub–Kahan form; forming D and calling ``eigh_tridiagonal`` loses ~κ(D)·ε on the small
modes (1e20 relative at 24 decades of contrast, measured). Masses and springs here span up to
about 23 decades (``exp(±26)``), for every kind of open chain end; the reference sees exactly
the float64 values the module computes (its own ``masses()`` and ``spring_constants()``).
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers import chain_toml, mp_dynamical_matrix

OPEN_ENDS = [("free", "free"), ("wall", "free"), ("free", "wall"), ("wall", "wall")]


def chain_text(left: str, right: str, n: int, spread: float, pm: float, pk: float) -> str:
    return chain_toml(n, left, right, name="graded", parameters={"spread": spread, "pm": pm, "pk": pk},
                      mass="exp(spread*sin(7.3*i + pm))", k="exp(spread*sin(3.1*i + pk))",
                      initial={"x": "0.01*sin(i)", "v": "0"})


def reference_omega2(masses: np.ndarray, ends: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Eigenvalues of D = M^-1/2 K M^-1/2 at 60 digits from the exact float64 inputs."""
    with mpmath.workdps(60):
        return np.array(sorted(float(x) for x in mpmath.eigsy(mp_dynamical_matrix(masses, ends, k), eigvals_only=True)))


def module_for(chain_module_of, left, right, n, spread, pm, pk):
    return chain_module_of(chain_text(left, right, n, spread, pm, pk), "graded")


def check(module, n: int) -> float:
    p = dict(module.DEFAULTS)
    got = module.omega2(**p, n=n)
    ref = reference_omega2(module.masses(**p, n=n), module.spring_ends(n=n), module.spring_constants(**p, n=n))
    rigid = int(module.RIGID_MODES)
    assert got.shape == (n,)
    assert np.all(got[:rigid] == 0.0)
    assert np.all(got[rigid:] > 0.0)
    return float(np.max(np.abs(got[rigid:] - ref[rigid:]) / ref[rigid:])) if n > rigid else 0.0


@pytest.mark.parametrize("ends", OPEN_ENDS, ids=lambda e: "-".join(e))
def test_graded_chain_omega2_is_accurate(chain_module_of, ends):
    """Alternating-like contrast of 23 decades: every ω² to ≤ 1e-13 relative."""
    worst = max(check(module_for(chain_module_of, *ends, n, 26.0, 0.4, 1.1), n) for n in (1, 2, 5, 12))
    assert worst <= 1e-13, worst


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(ends=st.sampled_from(OPEN_ENDS), n=st.integers(1, 14), spread=st.floats(0.0, 26.0),
       pm=st.floats(-3.0, 3.0), pk=st.floats(-3.0, 3.0))
def test_random_graded_chains(chain_module_of, ends, n, spread, pm, pk):
    assert check(module_for(chain_module_of, *ends, n, spread, pm, pk), n) <= 1e-13
