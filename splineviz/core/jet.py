"""Second-order forward-mode differentiation ("jets") for closed-form test functions.

A :class:`Jet` carries a value ``v`` of shape ``S``, first derivatives ``g`` of shape ``S + (m,)``
and second derivatives ``h`` of shape ``S + (m, m)`` along ``m`` seed directions. Arithmetic and
the elementary functions below propagate all three exactly (up to rounding), so a test function
written once as an expression yields exact gradients and Hessians without hand-derived formulas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Jet:
    """Value with first and second derivatives along ``m`` directions."""

    v: np.ndarray
    g: np.ndarray
    h: np.ndarray

    # make NumPy scalars and arrays defer to Jet's reflected operators
    __array_ufunc__ = None

    @staticmethod
    def variables(x, y, z, directions=None) -> tuple[Jet, Jet, Jet]:
        """Seed jets for the coordinates.

        Parameters
        ----------
        x, y, z : arrays of one shape S
        directions : (m, 3) array, optional
            Directions to differentiate along; the identity (full gradient and Hessian) if
            omitted.
        """
        x, y, z = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (x, y, z)))
        dirs = np.eye(3) if directions is None else np.asarray(directions, dtype=np.float64)
        m = dirs.shape[0]
        zero_h = np.zeros(x.shape + (m, m))
        return tuple(
            Jet(c, np.broadcast_to(dirs[:, axis], x.shape + (m,)), zero_h)
            for axis, c in enumerate((x, y, z))
        )

    # arithmetic ---------------------------------------------------------------------------
    def _lift(self, other) -> Jet:
        if isinstance(other, Jet):
            return other
        c = np.asarray(other, dtype=np.float64)
        return Jet(c, np.zeros(self.g.shape), np.zeros(self.h.shape))

    def __add__(self, other):
        o = self._lift(other)
        return Jet(self.v + o.v, self.g + o.g, self.h + o.h)

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.v, -self.g, -self.h)

    def __sub__(self, other):
        return self + (-self._lift(other))

    def __rsub__(self, other):
        return self._lift(other) - self

    def __mul__(self, other):
        if not isinstance(other, Jet):
            c = np.asarray(other, dtype=np.float64)
            return Jet(self.v * c, self.g * c[..., None], self.h * c[..., None, None])
        outer = self.g[..., :, None] * other.g[..., None, :]
        return Jet(
            self.v * other.v,
            self.g * other.v[..., None] + other.g * self.v[..., None],
            self.h * other.v[..., None, None] + other.h * self.v[..., None, None]
            + outer + np.swapaxes(outer, -1, -2),
        )

    __rmul__ = __mul__

    def __truediv__(self, other):
        if isinstance(other, Jet):
            return self * other.apply(1.0 / other.v, -1.0 / other.v**2, 2.0 / other.v**3)
        return self * (1.0 / np.asarray(other, dtype=np.float64))

    def __pow__(self, n: int):
        n = int(n)
        if n == 0:
            return self._lift(np.ones_like(self.v))
        if n == 1:
            return self
        return self.apply(self.v**n, n * self.v ** (n - 1), n * (n - 1) * self.v ** (n - 2))

    def apply(self, f0, f1, f2) -> Jet:
        """phi(self) from phi, phi', phi'' evaluated at ``self.v`` (chain rule)."""
        f1 = np.asarray(f1, dtype=np.float64)
        f2 = np.asarray(f2, dtype=np.float64)
        outer = self.g[..., :, None] * self.g[..., None, :]
        return Jet(
            np.asarray(f0, dtype=np.float64),
            f1[..., None] * self.g,
            f2[..., None, None] * outer + f1[..., None, None] * self.h,
        )


def exp(a: Jet) -> Jet:
    e = np.exp(a.v)
    return a.apply(e, e, e)


def sin(a: Jet) -> Jet:
    s, c = np.sin(a.v), np.cos(a.v)
    return a.apply(s, c, -s)


def cos(a: Jet) -> Jet:
    s, c = np.sin(a.v), np.cos(a.v)
    return a.apply(c, -s, -c)


def sqrt(a: Jet) -> Jet:
    """Square root; the derivatives are infinite where ``a.v == 0`` (as they truly are)."""
    r = np.sqrt(a.v)
    with np.errstate(divide="ignore", invalid="ignore"):
        return a.apply(r, 0.5 / r, -0.25 / (r * a.v))
