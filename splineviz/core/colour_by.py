"""Scalars to colour an isosurface by, at its ray hits ("Color by" of other viewers).

Every value comes from the spline itself at the hit: curvatures from its gradient and Hessian
(:mod:`splineviz.core.curvature`), the gradient magnitude, or the value of another volume's
spline there (e.g. a second channel). The colour map and range are applied by the view.

Conventions: hit points ``(N, 3)`` world coordinates; results ``(N,)`` float64, NaN where a
value is undefined (vanishing gradient, a point outside the other volume's box).
"""

from __future__ import annotations

import numpy as np

from splineviz.core.curvature import (
    MEASURES,
    curvature_field,
    principal_curvatures,
    spline_curvatures,
)
from splineviz.core.errors import SplinevizError

#: what an isosurface can be coloured by ("none": its flat colour)
FIELDS = ("none", *MEASURES, "gradient-magnitude", "volume", "distance")
#: colour maps offered (matplotlib names): the perceptually uniform sequential maps and a few
#: diverging ones for signed values such as curvatures
COLORMAPS = ("viridis", "plasma", "inferno", "magma", "cividis", "turbo", "coolwarm",
             "RdBu_r", "PuOr_r", "twilight")
#: how the colour range is chosen: the frame's values, given numbers, or symmetric about 0
RANGE_MODES = ("auto", "manual", "symmetric")
#: percentiles of the frame's values the automatic range spans (a few extreme pixels at
#: silhouettes or degenerate points would otherwise take the whole map)
AUTO_PERCENTILES = (2.0, 98.0)


class ColourByError(SplinevizError, ValueError):
    """Colour-by settings that cannot be used (unknown field, missing second volume)."""


def surface_distance(spline, iso: float, points: np.ndarray) -> np.ndarray:
    """Signed distance ``(N,)`` from points to the isosurface ``s = iso`` of another spline:
    the length of the Newton projection onto it, positive where ``s > iso``; NaN where the
    projection does not reach it (farther than a few grid steps, or no gradient).

    This is how two models (or two isovalues) of one volume differ, surface to surface: the
    comparison figures of the thesis as a colouring.
    """
    from splineviz.core.isosurface import project_to_isosurface

    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not len(p):
        return np.empty(0)
    lo, hi = spline.volume.finite_range
    tol = 1e-7 * max(hi - lo, 1e-300)
    proj, _ = project_to_isosurface(spline, p, iso, steps=12, tol=tol)
    value = spline.evaluate(p) - iso
    dist = np.linalg.norm(proj - p, axis=1) * np.sign(value)
    dist[np.abs(spline.evaluate(proj) - iso) > tol] = np.nan
    return dist


def hit_scalars(spline, points: np.ndarray, field: str, other=None,
                other_iso: float = 0.0) -> np.ndarray:
    """The scalar ``field`` at ``(N, 3)`` points of the isosurface of ``spline``.

    Parameters
    ----------
    spline : Spline
        The surface's model (derivatives for curvatures and the gradient magnitude).
    points : (N, 3)
    field : str, one of :data:`FIELDS` other than ``"none"``
    other : Spline, optional
        The second volume's spline (``"volume"``), or the spline of the surface to measure the
        distance to (``"distance"``, at ``other_iso``).
    other_iso : float

    Returns
    -------
    (N,) float64
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if field == "volume":
        if other is None:
            raise ColourByError("colouring by another volume needs that volume")
        out = np.full(len(p), np.nan)
        lo = np.array([b[0] for b in other.bounds])
        hi = np.array([b[1] for b in other.bounds])
        inside = np.all((p >= lo) & (p <= hi), axis=1)
        if inside.any():
            out[inside] = other.evaluate(p[inside])
        return out
    if field == "distance":
        if other is None:
            raise ColourByError("colouring by distance needs the other isosurface")
        return surface_distance(other, other_iso, p)
    if field == "gradient-magnitude":
        return np.linalg.norm(spline.gradient(p), axis=1) if len(p) else np.empty(0)
    if field in MEASURES:
        if not len(p):
            return np.empty(0)
        return curvature_field(field, *spline_curvatures(spline, p))
    raise ColourByError(f"unknown colour-by field {field!r}; choose one of {', '.join(FIELDS)}")


#: the fields that need only the gradient and Hessian at the hit (the ray caster's kernel
#: can return them: no spline evaluation after the cast)
DERIVATIVE_FIELDS = (*MEASURES, "gradient-magnitude")


def derivative_scalars(field: str, gradient: np.ndarray, hessian: np.ndarray) -> np.ndarray:
    """A field of :data:`DERIVATIVE_FIELDS` from gradients ``(N, 3)`` and Hessians
    ``(N, 3, 3)`` at the hits (e.g. from the kernel: ``Frame.hessian``) -> ``(N,)``."""
    if field == "gradient-magnitude":
        return np.linalg.norm(gradient, axis=1)
    if field not in MEASURES:
        raise ColourByError(f"{field!r} is not computed from derivatives")
    return curvature_field(field, *principal_curvatures(gradient, hessian))


def scalar_range(values: np.ndarray, mode: str = "auto", vmin: float = 0.0,
                 vmax: float = 1.0) -> tuple[float, float]:
    """The range ``(lo, hi)`` the colour map spans.

    Parameters
    ----------
    values : (N,) the frame's scalars (NaN ignored)
    mode : ``"auto"`` (the ``AUTO_PERCENTILES`` of the values), ``"symmetric"`` (the same,
        widened to ``(-m, m)``: signed curvatures), ``"manual"`` (``vmin, vmax``)
    vmin, vmax : float, the manual range

    Returns
    -------
    (lo, hi) with lo < hi
    """
    if mode == "manual":
        lo, hi = float(vmin), float(vmax)
    elif mode in ("auto", "symmetric"):
        v = np.asarray(values, dtype=np.float64)
        v = v[np.isfinite(v)]
        if v.size == 0:
            return (-1.0, 1.0) if mode == "symmetric" else (0.0, 1.0)
        lo, hi = (float(x) for x in np.percentile(v, AUTO_PERCENTILES))
        if mode == "symmetric":
            m = max(abs(lo), abs(hi))
            lo, hi = -m, m
    else:
        raise ColourByError(f"unknown range mode {mode!r}; choose one of "
                            f"{', '.join(RANGE_MODES)}")
    if not hi > lo:
        # a constant field: a range around it, so the map shows its middle colour
        pad = max(abs(lo), 1.0) * 1e-6
        lo, hi = lo - pad, hi + pad
    return lo, hi
