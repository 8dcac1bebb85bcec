"""A linear scene as a state-space model ``ẋ = A x + B u``, ``y = C x + D u`` (SciPy, python-control).

The state is ``(x, v)``: the displacements (from the springs' rest configuration) and velocities of
the masses, ``A = [[0, I], [−M⁻¹K, −M⁻¹C]]`` with K and C stamped from the elements (springs by
their linear stiffness; dashpots, Rayleigh ``αM + βK``, modal damping ``M Φ diag(2ζω) Φᵀ M``).
Inputs are forces on masses (``B = [0; M⁻¹ e_k]``) or a base acceleration a_g (relative
coordinates: every mass feels ``−a_g``, ``B = [0; −1]``). Outputs are displacements, velocities or
accelerations of masses; with a base input, displacements and velocities are relative to the base
and accelerations absolute (what an accelerometer on the mass reads: ``D`` gains 1 per base column).

``[chain]`` scenes are built as ``scipy.sparse`` CSR matrices (never 2N × 2N dense).

Accuracy: A holds ``M⁻¹K`` formed in float64, so the model's poles and frequency response lose about
(element contrast) × ε relative where stiffnesses or masses span many decades —
:func:`contrast_note` says so; :func:`springchain.frf` solves from the elements instead.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse

from ..modes.elements import Elements

#: Element contrast (largest over smallest mass, spring or dashpot) above which a note is given.
CONTRAST_NOTE = 1e6
#: Output kinds and their spellings.
KINDS = {"x": "displacement", "displacement": "displacement", "v": "velocity", "velocity": "velocity",
         "a": "acceleration", "acceleration": "acceleration"}
GROUND = "ground"


@dataclass(frozen=True)
class StateSpaceModel:
    """``A (2N, 2N)``, ``B (2N, U)``, ``C (Y, 2N)``, ``D (Y, U)``: dense arrays, or CSR for ``[chain]`` scenes.

    Attributes
    ----------
    inputs, outputs, states : tuple of str
        Names (``"F_m1"``/``"a_ground"``; ``"x_m1"``, ``"v_m1"``, ``"a_m1"``; ``"x_m1"``, ``"v_m1"``).
    notes : list of str
    """

    A: object = field(repr=False)
    B: object = field(repr=False)
    C: object = field(repr=False)
    D: object = field(repr=False)
    inputs: tuple = ()
    outputs: tuple = ()
    states: tuple = ()
    notes: list = field(default_factory=list, repr=False)

    @property
    def sparse(self) -> bool:
        return scipy.sparse.issparse(self.A)

    def dense(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` as dense arrays."""
        return tuple(m.toarray() if scipy.sparse.issparse(m) else np.asarray(m) for m in (self.A, self.B, self.C, self.D))

    def freqresp(self, omega: np.ndarray) -> np.ndarray:
        """``C (iωI − A)⁻¹ B + D``, shape (Y, U, W), complex (a sparse or dense solve per frequency)."""
        omega = np.asarray(omega, dtype=float).reshape(-1)
        n = self.A.shape[0]
        out = np.empty((self.C.shape[0], self.B.shape[1], omega.shape[0]), dtype=complex)
        if self.sparse:
            import scipy.sparse.linalg as sla

            eye = scipy.sparse.identity(n, format="csc")
            A = self.A.tocsc()
            B = self.B.toarray()
            for j, w in enumerate(omega):
                X = sla.spsolve(1j * w * eye - A, B.astype(complex))
                out[:, :, j] = self.C @ X.reshape(n, -1) + self.D.toarray()
            return out
        A, B, C, D = self.dense()
        for j, w in enumerate(omega):
            out[:, :, j] = C @ np.linalg.solve(1j * w * np.eye(n) - A, B.astype(complex)) + D
        return out


def contrast(el: Elements) -> float:
    """Largest over smallest nonzero mass, spring and dashpot (each kind apart), as :mod:`numeric.frf.response` counts."""
    out = 1.0
    for v in (el.stiffness, el.damping, el.masses):
        v = np.abs(np.asarray(v, dtype=float))
        v = v[v > 0]
        if v.size:
            out = max(out, float(v.max() / v.min()))
    return out


def contrast_note(el: Elements) -> str | None:
    """The one-line note where the state-space form loses accuracy (None below :data:`CONTRAST_NOTE`)."""
    c = contrast(el)
    if c <= CONTRAST_NOTE:
        return None
    return (f"state-space form at element contrast {c:.2g}: A holds M^-1 K formed in float64, so its poles and "
            f"frequency response lose about {c * np.finfo(float).eps:.1g} relative; springchain.frf solves from the "
            "elements and stays accurate")


def stamp(n: int, ends: np.ndarray, values: np.ndarray):
    """``Σ v (e_a − e_b)(e_a − e_b)ᵀ`` as CSR (walls omitted)."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    values = np.asarray(values, dtype=float)
    rows, cols, vals = [], [], []
    for ci, si in ((0, 1.0), (1, -1.0)):
        for cj, sj in ((0, 1.0), (1, -1.0)):
            ok = (ends[:, ci] >= 0) & (ends[:, cj] >= 0) & (ends[:, 0] != ends[:, 1])
            rows.append(ends[ok, ci])
            cols.append(ends[ok, cj])
            vals.append(si * sj * values[ok])
    return scipy.sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                   shape=(n, n)).tocsr()


def damping_of(el: Elements, K):
    n = el.n
    C = stamp(n, el.damper_ends, el.damping)
    if el.rayleigh is not None:
        a, b = el.rayleigh
        C = C + a * scipy.sparse.diags(el.masses) + b * K
    if el.modal_zeta is not None:
        from ..modes.spectrum import spectrum

        spec = spectrum(el.masses, el.spring_ends, el.stiffness)
        MPhi = el.masses[:, None] * spec.shapes
        C = C + scipy.sparse.csr_matrix((MPhi * (2.0 * el.modal_zeta * spec.omega)[None, :]) @ MPhi.T)
    return C.tocsr()


def state_space(el: Elements, names: tuple[str, ...], inputs: list, outputs: list, *, sparse: bool) -> StateSpaceModel:
    """The state-space model of a linear scene.

    Parameters
    ----------
    el : Elements
    names : tuple of str
        Mass names, length N.
    inputs : list of int or "ground"
        A mass index (a force on it) or :data:`GROUND` (a base acceleration).
    outputs : list of (int, str)
        ``(mass index, kind)`` with kind ``"displacement"``, ``"velocity"`` or ``"acceleration"``.
    sparse : bool
        CSR matrices (``[chain]`` scenes) instead of dense arrays.
    """
    n = el.n
    K = stamp(n, el.spring_ends, el.stiffness)
    C = damping_of(el, K)
    minv = scipy.sparse.diags(1.0 / el.masses)
    zero, eye = scipy.sparse.csr_matrix((n, n)), scipy.sparse.identity(n, format="csr")
    A = scipy.sparse.bmat([[zero, eye], [-(minv @ K), -(minv @ C)]], format="csr")
    B = np.zeros((2 * n, len(inputs)))
    ground_cols = []
    for j, u in enumerate(inputs):
        if u == GROUND:
            B[n:, j] = -1.0
            ground_cols.append(j)
        else:
            B[n + u, j] = 1.0 / el.masses[u]
    Crows = scipy.sparse.lil_matrix((len(outputs), 2 * n))
    D = np.zeros((len(outputs), len(inputs)))
    accel = A[n:].tolil()
    for r, (i, kind) in enumerate(outputs):
        if kind == "displacement":
            Crows[r, i] = 1.0
        elif kind == "velocity":
            Crows[r, n + i] = 1.0
        else:  # acceleration: the velocity rows of A and B; absolute under a base input
            Crows[r] = accel[i]
            D[r] = B[n + i]
            D[r, ground_cols] += 1.0
    kinds = {"displacement": "x", "velocity": "v", "acceleration": "a"}
    in_names = tuple("a_ground" if u == GROUND else f"F_{names[u]}" for u in inputs)
    out_names = tuple(f"{kinds[k]}_{names[i]}" for i, k in outputs)
    states = tuple(f"x_{m}" for m in names) + tuple(f"v_{m}" for m in names)
    notes = [nt for nt in (contrast_note(el),) if nt]
    if sparse:
        return StateSpaceModel(A, scipy.sparse.csr_matrix(B), Crows.tocsr(), scipy.sparse.csr_matrix(D),
                               in_names, out_names, states, notes)
    return StateSpaceModel(A.toarray(), B, Crows.toarray(), D, in_names, out_names, states, notes)


__all__ = ["StateSpaceModel", "state_space", "contrast", "contrast_note", "KINDS", "GROUND", "CONTRAST_NOTE"]


def siso_zpk(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
             derivative: tuple[np.ndarray, int] | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles and gain of a SISO model by eigenvalue problems, not polynomial roots.

    Poles: the eigenvalues of A. Zeros: the finite generalized eigenvalues of the Rosenbrock pencil
    ``([[A, B], [C, D]], [[I, 0], [0, 0]])`` (QZ), as many as the state count less the relative
    degree (the first Markov parameter ``C A^(r−1) B`` that is structurally nonzero), each refined by two
    Newton steps on ``H(s) = 0`` with the solve (``H' = −C (sI − A)⁻² B``). Gain: from one solve
    ``H(s₀) = C (s₀I − A)⁻¹ B + D`` at ``s₀ = i·ω`` near the geometric mean of |poles| and away from every pole and zero, so the product form
    ``k Π(s − z) / Π(s − p)`` equals the solve there. (SciPy's own conversion goes through the
    characteristic polynomial: 1e-7 … 3e-5 relative on a three-storey building.)

    ``derivative = (C_x, k)``: the output is the k-th derivative of the displacement output ``C_x``
    (velocity k = 1, acceleration k = 2, under forces): its zeros are those of ``C_x`` and k exact
    zeros at s = 0, its gain the same.
    """
    import scipy.linalg

    if derivative is not None:
        cx, k = derivative
        z, p, g = siso_zpk(A, B, cx, np.zeros((1, 1)))
        return np.concatenate([z, np.zeros(k)]), p, g

    n = A.shape[0]
    poles = scipy.linalg.eigvals(A)
    if np.any(D != 0):
        r = 0
    else:  # the structural relative degree: C A^(r-1) B on the sparsity patterns (no rounding to judge)
        r, v = None, B[:, 0] != 0
        pattern = A != 0
        for k in range(1, n + 1):
            if np.any(C[0][v] != 0):
                r = k
                break
            v = (pattern[:, v].any(axis=1)) | False
        if r is None:
            return np.zeros(0), poles, 0.0
    M1 = np.block([[A, B], [C, D]])
    M2 = np.zeros_like(M1)
    M2[:n, :n] = np.eye(n)
    alpha, beta = scipy.linalg.eig(M1, M2, right=False, homogeneous_eigvals=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = alpha / beta
    finite = np.isfinite(lam)
    order = np.argsort(np.where(finite, np.abs(lam), np.inf))
    zeros = lam[order[: n - r]]
    eye = np.eye(n)
    for j, z in enumerate(zeros):  # two Newton steps on H(s) = 0 with the solve: the zero to the solve's accuracy
        for _ in range(2):
            x = np.linalg.solve(z * eye - A, B[:, 0].astype(complex))
            h, dh = complex(C[0] @ x + D[0, 0]), complex(-C[0] @ np.linalg.solve(z * eye - A, x))
            step = h / dh if dh != 0 else np.inf
            if not abs(step) <= 1e-6 * abs(z):  # a refinement only, never a jump to another zero
                break
            z = z - step
        zeros[j] = z
    mag = np.abs(poles[np.abs(poles) > 0])
    mid = float(np.exp(np.mean(np.log(mag)))) if mag.size else 1.0
    near = np.concatenate([poles, zeros])  # s0 away from every pole and zero (relative to |s0|)
    s0 = max((1j * mid * f for f in (1.0, 0.31, 3.7, 0.13, 8.1, 0.05, 21.0)),
             key=lambda c: float(np.min(np.abs(c - near), initial=np.inf)) / abs(c))
    h0 = complex((C @ np.linalg.solve(s0 * np.eye(n) - A, B.astype(complex)) + D)[0, 0])
    gain = h0 * np.prod(s0 - poles) / np.prod(s0 - zeros)
    return zeros, poles, float(gain.real)


__all__ += ["siso_zpk"]
