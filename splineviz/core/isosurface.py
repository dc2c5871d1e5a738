"""Points on a spline isosurface: Newton projection along the spline gradient.

Shared by the mesh exports (:mod:`splineviz.render.extract`, the advancing front of
:mod:`splineviz.pointcloud.spline_mesh`).
"""

from __future__ import annotations

import numpy as np


def project_to_isosurface(spline, points: np.ndarray, iso: float, steps: int = 6,
                          tol: float | None = None):
    """Newton steps x <- x - (s(x) - iso) grad s / |grad s|^2, kept inside the data box.

    Parameters
    ----------
    spline : Spline
    points : (N, 3) starting points near the isosurface
    iso : float
    steps : int, most Newton steps
    tol : float, optional
        Stop early once every ``|s(x) - iso| <= tol`` (single points of the advancing front
        need one or two steps, not six).

    Returns
    -------
    points : (N, 3) projected points
    normals : (N, 3) unit normals -grad s / |grad s| there (VTK's contour convention: they point
        to lower values); zero where the gradient vanishes
    """
    lo = np.array([b[0] for b in spline.bounds])
    hi = np.array([b[1] for b in spline.bounds])
    x = np.asarray(points, dtype=np.float64).copy()
    # vertices on a face of the box slide within that face (the cut of the surface stays exact)
    face = 1e-9 * np.max(hi - lo)
    free = ~((np.abs(x - lo) < face) | (np.abs(x - hi) < face))
    step_limit = 0.5 * np.min(spline.volume.spacing)
    g = None
    for _ in range(steps):
        v, g = spline.value_gradient(x)
        if tol is not None and np.all(np.abs(v - iso) <= tol):
            break
        g = g * free
        g2 = np.einsum("nc,nc->n", g, g)
        ok = g2 > 1e-30
        delta = np.zeros_like(x)
        delta[ok] = ((v[ok] - iso) / g2[ok])[:, None] * g[ok]
        # never move further than half a voxel: a vertex belongs to the sheet it started on
        norm = np.linalg.norm(delta, axis=1)
        scale = np.minimum(1.0, step_limit / np.maximum(norm, 1e-300))
        x = np.clip(x - delta * scale[:, None], lo, hi)
        g = None
    if g is None:
        # the gradient at the final points (not yet evaluated after the last step)
        g = spline.gradient(x)
    n = np.linalg.norm(g, axis=1)
    normals = np.divide(-g, n[:, None], out=np.zeros_like(g), where=n[:, None] > 0)
    return x, normals
