"""The cubic C^1 quasi-interpolating spline on the type-6 partition (thesis §4.4, [SZ07b]).

``model="cubic-c1"``: on each of the 24 tetrahedra of the cube around data point f_ijk the
spline is a cubic polynomial whose 20 B-coefficients are fixed weighted sums of the 27 values
f_{i+a, j+b, k+c}, a, b, c in {-1, 0, 1} (eq. 4.3; 23 of them are used per tetrahedron). The
spline is C^1 everywhere, reproduces 1, x, y, z, xy, xz, yz, xyz and maps x^2 to x^2 + h^2/4,
so values and gradients converge with order two. Its determining set per cube has 56
coefficients (xi_00kl, k + l = 3, and xi_0111 of every tetrahedron); the other 119 follow by
the averaging rules of :mod:`~splineviz.core.splines.type6_rules` (Fig. 4.5).
"""

from __future__ import annotations

from splineviz.core.splines.type6_spline import Type6Spline


class CubicC1Spline(Type6Spline):
    """Cubic C^1 spline S_3^1(Delta_6) of a volume (thesis §4.4).

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array

    Examples
    --------
    >>> import numpy as np
    >>> from splineviz.core.splines.cubic_c1 import CubicC1Spline
    >>> i, j, k = np.indices((5, 5, 5))
    >>> s = CubicC1Spline(i * j * k)        # xyz is reproduced exactly
    >>> float(s.evaluate([[1.3, 2.2, 0.7]])[0])  # doctest: +ELLIPSIS
    2.002...
    """

    model = "cubic-c1"
    scheme_name = "cubic-c1"
