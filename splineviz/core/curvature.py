"""Curvatures of isosurfaces from the gradient and Hessian of the field (Kindlmann et al.
2003, "Curvature-based transfer functions for direct volume rendering", §3).

With the surface normal ``n = -g / |g|`` (pointing to lower values, VTK's contour convention)
and the tangent projector ``P = I - n n^T``, the geometry tensor ``G = -P H P / |g|`` has the
principal curvatures ``k1 >= k2`` as its two nonzero eigenvalues; they follow from its trace
``T = k1 + k2`` and Frobenius norm ``F^2 = k1^2 + k2^2``. Sign: positive where the surface
bulges towards lower values (a ball of high values, as CT data of objects, is convex with
positive curvatures); a field increasing outwards, like a distance field, gives negative ones.

Conventions: gradients ``(N, 3)``, Hessians ``(N, 3, 3)``; every result ``(N,)`` float64, NaN
where the gradient vanishes.
"""

from __future__ import annotations

import numpy as np

#: names of :func:`curvature_field`, in the order of the GUI's list
MEASURES = ("mean", "gaussian", "k1", "k2", "shape-index", "curvedness")


def principal_curvatures(gradient: np.ndarray, hessian: np.ndarray):
    """Principal curvatures of the isosurfaces through the points.

    Parameters
    ----------
    gradient : (N, 3)
    hessian : (N, 3, 3) symmetric

    Returns
    -------
    k1, k2 : (N,) each, ``k1 >= k2``; NaN where ``|g| = 0``
    """
    g = np.asarray(gradient, dtype=np.float64)
    h = np.asarray(hessian, dtype=np.float64)
    norm = np.linalg.norm(g, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = -g / norm[:, None]
        p = np.eye(3) - n[:, :, None] * n[:, None, :]
        geom = -np.einsum("nij,njk,nkl->nil", p, h, p) / norm[:, None, None]
        trace = np.einsum("nii->n", geom)
        frob2 = np.einsum("nij,nij->n", geom, geom)
        # 2 F^2 - T^2 = (k1 - k2)^2 >= 0 up to rounding
        root = np.sqrt(np.maximum(2.0 * frob2 - trace * trace, 0.0))
    k1 = 0.5 * (trace + root)
    k2 = 0.5 * (trace - root)
    bad = ~(norm > 0)
    k1[bad] = np.nan
    k2[bad] = np.nan
    return k1, k2


def curvature_field(measure: str, k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """One curvature measure from the principal curvatures ``(N,)`` -> ``(N,)``.

    ``mean`` (k1 + k2) / 2, ``gaussian`` k1 k2, ``k1``, ``k2``, ``shape-index``
    (2 / pi) arctan((k1 + k2) / (k1 - k2)) in [-1, 1] (Koenderink; 1 for a cap, 0 for a
    saddle-symmetric point, umbilics give +-1), ``curvedness`` sqrt((k1^2 + k2^2) / 2).
    """
    if measure == "mean":
        return 0.5 * (k1 + k2)
    if measure == "gaussian":
        return k1 * k2
    if measure == "k1":
        return np.array(k1, dtype=np.float64)
    if measure == "k2":
        return np.array(k2, dtype=np.float64)
    if measure == "shape-index":
        # arctan2 gives +-pi/2 at umbilics (k1 = k2) instead of dividing by zero
        return (2.0 / np.pi) * np.arctan2(k1 + k2, k1 - k2)
    if measure == "curvedness":
        return np.sqrt(0.5 * (k1 * k1 + k2 * k2))
    raise ValueError(f"unknown curvature measure {measure!r}; choose one of "
                     f"{', '.join(MEASURES)}")


def spline_curvatures(spline, points: np.ndarray):
    """Principal curvatures ``k1, k2 (N,)`` of the spline's isosurfaces at ``(N, 3)`` points
    (one pass for gradient and Hessian)."""
    out = spline._run(points, 2)
    return principal_curvatures(out[:, 1:4], out[:, 4:].reshape(-1, 3, 3))
