"""Closed-form test functions of the thesis with exact first and second derivatives.

Each :class:`TestFunction` is written once as an expression over :class:`~splineviz.core.jet.Jet`
numbers, so values, gradients and Hessians come from the same formula (forward-mode
differentiation, exact up to rounding). Call signatures take coordinate arrays of any (equal)
shape ``S``: ``f(x, y, z) -> S``, ``f.gradient(x, y, z) -> S + (3,)``,
``f.hessian(x, y, z) -> S + (3, 3)``, and ``f.derivatives(x, y, z, directions)`` for
derivatives along chosen directions only (cheaper, e.g. D_x and D_xx for the tables of §5.5).

Functions
---------
blob, fr (Franke type), ml (Marschner-Lobb, alpha = 1/4, f_M = 6): thesis §5.5.
barth: Barth's sextic (§5.6, Fig. 5.7). chmutov: Fig. 6.20. x2 and f1: Remark 3.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from splineviz.core import jet
from splineviz.core.jet import Jet


@dataclass(frozen=True)
class TestFunction:
    """A scalar field with exact derivatives.

    Attributes
    ----------
    name : short name used in tables and the "Sources" plugin
    expression : callable (Jet, Jet, Jet) -> Jet
    domain : ((xmin, xmax), (ymin, ymax), (zmin, zmax)) where the function is usually sampled
    isovalue : a typical isovalue for pictures
    """

    name: str
    expression: Callable[[Jet, Jet, Jet], Jet]
    domain: tuple = ((-0.5, 0.5),) * 3
    isovalue: float = 0.0
    description: str = ""

    __test__ = False  # not a pytest test class

    def derivatives(self, x, y, z, directions=None) -> Jet:
        """Value and derivatives along ``directions`` ((m, 3); all axes if omitted)."""
        return self.expression(*Jet.variables(x, y, z, directions))

    def __call__(self, x, y, z) -> np.ndarray:
        return self.derivatives(x, y, z, np.zeros((0, 3))).v

    def gradient(self, x, y, z) -> np.ndarray:
        return self.derivatives(x, y, z).g

    def hessian(self, x, y, z) -> np.ndarray:
        return self.derivatives(x, y, z).h


def _cos_sqrt(a: Jet, k: float) -> Jet:
    """cos(k sqrt(a)) for a >= 0, smooth at a = 0 (series there; it is analytic in a)."""
    u = np.maximum(a.v, 0.0)
    s = np.sqrt(u)
    small = s * k < 1e-3
    ss = np.where(small, 1.0, s)  # avoid 0/0 in the branch not taken
    ks = k * ss
    f0 = np.cos(k * s)
    f1 = np.where(small, -k**2 / 2 + k**4 * u / 12, -k * np.sin(ks) / (2 * ss))
    f2 = np.where(
        small,
        k**4 / 12 - k**6 * u / 120,
        -k * (ks * np.cos(ks) - np.sin(ks)) / (4 * ss**3),
    )
    return a.apply(f0, f1, f2)


def _blob(x, y, z):
    return (jet.exp(-5 * ((x - 0.5) ** 2 + y**2 + z**2))
            + jet.exp(-5 * (x**2 + (y - 0.5) ** 2 + z**2)))


def _franke(x, y, z):
    return (
        0.5 * jet.exp(-10 * ((x - 0.25) ** 2 + (y - 0.25) ** 2))
        + 0.75 * jet.exp(-16 * ((x - 0.25) ** 2 + (y - 0.25) ** 2 + (z - 0.25) ** 2))
        + 0.5 * jet.exp(-10 * ((x - 0.75) ** 2 + (y - 0.125) ** 2 + (z - 0.5) ** 2))
        - 0.25 * jet.exp(-20 * ((x - 0.75) ** 2 + (y - 0.75) ** 2))
    )


ML_ALPHA = 0.25
ML_FM = 6.0


def _marschner_lobb(x, y, z):
    # rho_r(r) = cos(2 pi f_M cos(pi r / 2)), r = sqrt(x^2 + y^2)
    inner = _cos_sqrt(x**2 + y**2, np.pi / 2)
    rho = jet.cos(2 * np.pi * ML_FM * inner)
    return (1 - jet.sin(np.pi * z / 2) + ML_ALPHA * (1 + rho)) / (2 * (1 + ML_ALPHA))


TAU = 0.5 * (1 + np.sqrt(5.0))


def _barth(x, y, z, w=1.0):
    t2 = TAU**2
    x2, y2, z2 = x**2, y**2, z**2
    return 4 * (t2 * x2 - y2) * (t2 * y2 - z2) * (t2 * z2 - x2) - (1 + 2 * TAU) * (
        (x2 + y2 + z2 - w**2) ** 2
    ) * w**2


def _chmutov(x, y, z):
    return x**16 + y**16 + z**16 - jet.cos(7 * x) - jet.cos(7 * y) - jet.cos(7 * z)


def _x2(x, y, z):
    return x**2


def _f1(x, y, z):
    return x * y + x * z + y * z + x + y + z + 1


blob = TestFunction("blob", _blob, isovalue=0.5, description="two blended metaballs (§5.5)")
fr = TestFunction("fr", _franke, isovalue=0.3, description="Franke-type exponentials (§5.5)")
ml = TestFunction(
    "ml", _marschner_lobb, domain=((-1.0, 1.0),) * 3, isovalue=0.5,
    description="Marschner-Lobb, alpha = 1/4, f_M = 6 (§5.5)",
)
barth = TestFunction(
    "barth", _barth, domain=((-1.8, 1.8),) * 3, isovalue=0.0,
    description="Barth's sextic, w = 1 (§5.6, Fig. 5.7)",
)
chmutov = TestFunction(
    "chmutov", _chmutov, domain=((-1.0, 1.0),) * 3, isovalue=-2.0,
    description="Chmutov type x^16 + y^16 + z^16 - cos 7x - cos 7y - cos 7z (Fig. 6.20)",
)
x2 = TestFunction("x2", _x2, description="x^2 (Remark 3)")
f1 = TestFunction("f1", _f1, description="xy + xz + yz + x + y + z + 1 (Remark 3)")

#: name -> function
TEST_FUNCTIONS: dict[str, TestFunction] = {
    f.name: f for f in (blob, fr, ml, barth, chmutov, x2, f1)
}

# readable aliases
franke = fr
marschner_lobb = ml
barth_sextic = barth
