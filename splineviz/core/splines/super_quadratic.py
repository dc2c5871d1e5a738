"""The quadratic super spline on the type-6 partition (thesis §4.4, [NRSZ05, RZNS04a]).

``model="super-quadratic"``: on each of the 24 tetrahedra of the cube around data point f_ijk
the spline is a quadratic polynomial whose 10 B-coefficients are weighted sums of the 27 data
values around f_ijk (eq. 4.3; 15 of them per tetrahedron).

Which rules ship: the original papers' formula sections could not be obtained (their stored
copies expose only the opening pages), so this is the reconstruction documented in
``spec/type6-formulas.md``: the unique cube-symmetric scheme on the 27-neighbourhood that is
continuous, reproduces linear polynomials and xy, xz, yz, maps x^2 to x^2 + h^2/4 and is C^1 at
cube centres, face centres, across cube faces and across the interior triangles
[v0, v1, corner]; it is *not* C^1 across the 12 triangles [v0, v2, v3] nor at cube vertices.
Its maximal Marschner-Lobb error at 41^3 (0.087) matches the figure of the Vis 2003 paper
(0.088). Because the rules are not C^1 at cube vertices, the 20 coefficients on the cube edges
do not determine the cube: the coefficient functionals span 24 dimensions, so the determining
set here has 24 values (8 vertices, 12 edge midpoints, centre and three ring-1 points) instead
of the thesis' 20.
"""

from __future__ import annotations

from splineviz.core.splines.type6_spline import Type6Spline


class SuperQuadraticSpline(Type6Spline):
    """Quadratic super spline S_2^{0,1}(Delta_6) of a volume (thesis §4.4).

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array

    Examples
    --------
    >>> import numpy as np
    >>> from splineviz.core.splines.super_quadratic import SuperQuadraticSpline
    >>> i, j, k = np.indices((5, 5, 5))
    >>> s = SuperQuadraticSpline(i * j + k)   # xy and linear terms are reproduced
    >>> float(s.evaluate([[1.3, 2.2, 0.7]])[0])  # doctest: +ELLIPSIS
    3.56...
    """

    model = "super-quadratic"
    scheme_name = "super-quadratic"
