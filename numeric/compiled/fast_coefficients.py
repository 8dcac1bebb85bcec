"""The numbers of a chain's stencil at fixed parameter values (:class:`ChainCoefficients`),
read from a generated ``[chain]`` module."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from ...generated.contract import End
from ..errors import RunRefused
from ..system import System, interface


@dataclass(frozen=True)
class ChainCoefficients:
    """The numbers of a chain's stencil at fixed parameter values.

    Attributes
    ----------
    n : int
        Number of masses.
    left, right : End
        The ends (``RING`` on both or neither).
    inv_mass : ndarray, shape (n,), or (1,) for a uniform chain
        ``1/m_i``.
    k : ndarray, shape (max(n-1, 1),), or (1,) for a uniform chain
        Spring ``i`` joins masses ``i`` and ``i+1``.
    k3 : ndarray, same shape as ``k``, or None
        Cubic coefficients (None for a linear chain).
    k_left, k_right : float
        The left wall spring; the right wall spring or the ring's closing spring (0 if absent).
    k3_left, k3_right : float
        Their cubic coefficients (0 if absent or linear).
    uniform : bool
        Coefficients independent of the index (arrays of length 1).
    law : numeric.compiled.potential_law.CompiledLaw or None
        A spring potential's kernels and parameter values (:func:`numeric.compiled.potential_law.compiled_law`);
        then ``k`` holds the stiffness V''(0) (for the ω_max bound) and the law's kernels take the
        parameter values in k3's place (V'(d) instead of k d + k3 d³). None otherwise.
    """

    n: int
    left: End
    right: End
    inv_mass: np.ndarray = field(repr=False)
    k: np.ndarray = field(repr=False)
    k3: np.ndarray | None = field(repr=False)
    k_left: float
    k_right: float
    k3_left: float
    k3_right: float
    uniform: bool
    law: object = field(default=None, repr=False, compare=False)

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None,
                    n: int | None = None) -> "ChainCoefficients":
        """Read the coefficients from a generated ``[chain]`` module.

        Parameters
        ----------
        module : module
            A generated chain module (``CHAIN = True``).
        params : dict, optional
            Parameter values overriding the module's defaults.
        n : int, optional
            Number of masses (default the module's N).
        """
        if n is not None and int(n) < 1:
            raise ValueError(f"a chain needs n >= 1 masses, got {n}")
        if not interface(module).chain:
            raise RunRefused("the fused chain step needs a [chain] scene's generated module")
        return cls.from_system(System.from_module(module, params, n=n))

    @classmethod
    def from_system(cls, system: System) -> "ChainCoefficients":
        """Read the coefficients of a ``[chain]`` :class:`System` (its size and parameter values)."""
        if not system.chain:
            raise RunRefused("the fused chain step needs a [chain] scene's generated module")
        n = system.n
        left, right = system.ends
        uniform = system.uniform
        m = system.masses
        ks = system.stiffness
        off = 1 if left is End.WALL else 0
        inner = ks[off:off + n - 1]
        k_left = float(ks[0]) if left is End.WALL else 0.0
        k_right = float(ks[-1]) if right in (End.WALL, End.RING) else 0.0
        k3 = None
        k3_left = k3_right = 0.0
        law = None
        if system.potential:  # a spring potential: the compiled law (index-free laws only)
            from .potential_law import compiled_law

            law = None if system.law_indexed else compiled_law(system)
        elif not system.linear:  # spring_cubic_constants(): spring_constants() order
            k3s = system.cubic_stiffness
            k3 = np.array(k3s[off:off + n - 1])
            if left is End.WALL:
                k3_left = float(k3s[0])
            if right in (End.WALL, End.RING):
                k3_right = float(k3s[-1])
        if uniform:
            inv = np.array([1.0 / m[0]])
            kk = np.array([inner[0] if n > 1 else (k_right or k_left or 0.0)])
            k3a = None if k3 is None else np.array([k3[0] if n > 1 else (k3_right or k3_left)])
        else:
            inv = 1.0 / m
            kk = inner.copy() if n > 1 else np.zeros(1)
            k3a = None if k3 is None else (k3.copy() if n > 1 else np.zeros(1))
        return cls(n, left, right, inv, kk, k3a, k_left, k_right, k3_left, k3_right, uniform, law)

    @property
    def cubic(self) -> bool:
        return self.k3 is not None

    @property
    def omega_max_bound(self) -> float:
        """Gershgorin bound on ω_max (:func:`numeric.modes.bounds.chain_omega2_bound`; ≥ the true ω_max)."""
        from ..modes.bounds import chain_omega2_bound

        inner = self.k if self.n > 1 else np.zeros(0)
        ring = self.right is End.RING
        return math.sqrt(chain_omega2_bound(self.n, self.inv_mass, inner, self.k_left, self.k_right, ring))

    def kernel_args(self) -> tuple:
        """The positional coefficient arguments of the compiled sweeps.

        Floats for a uniform chain and arrays otherwise (the kernels are
        specialised on these types); None for the cubic ones of a linear chain.
        """
        if self.law is not None:  # the law is the whole tension: linear coefficients 0, the law in k3's place
            im = float(self.inv_mass[0]) if self.uniform else self.inv_mass
            k = 0.0 if self.uniform else np.zeros_like(self.k)
            c = self.law.args
            return (self.n, im, k, c, 0.0, 0.0, c, c, self.left.code, self.right.code)
        if self.uniform:
            im, k = float(self.inv_mass[0]), float(self.k[0])
            k3 = None if self.k3 is None else float(self.k3[0])
        else:
            im, k, k3 = self.inv_mass, self.k, self.k3
        k3l = None if self.k3 is None else self.k3_left
        k3r = None if self.k3 is None else self.k3_right
        return (self.n, im, k, k3, self.k_left, self.k_right, k3l, k3r, self.left.code, self.right.code)
