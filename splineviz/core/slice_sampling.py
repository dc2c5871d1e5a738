"""A spline on an axis-aligned slice: the sampled image, the exact isosurface contour, probes.

A slice view shows a plane ``x[axis] = position`` of a volume through a spline model: the
image is the spline evaluated on a regular grid of the plane (finer than the data grid, so
the smooth models look smooth), and the contour of an isosurface is the exact cross section
of :func:`splineviz.core.sections.plane_section` (every vertex on the isosurface to
rounding, not to the pixel grid).

Conventions: world coordinates; a slice is described in its own 2-D frame ``(u, v)``, the
world coordinates along its two in-plane axes ``(u_axis, v_axis)`` (increasing order of
the remaining axes). Images are ``(nv, nu)`` float64, row ``j`` at ``vs[j]``, column ``i``
at ``us[i]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splineviz.core import sections
from splineviz.core.errors import SplinevizError

#: most samples of one slice image (bounds the time of one slice on large volumes)
MAX_SLICE_SAMPLES = 1_000_000


class SliceError(SplinevizError, ValueError):
    """A slice that cannot be taken (an axis that is not 0, 1 or 2)."""


def in_plane_axes(axis: int) -> tuple[int, int]:
    """The two axes ``(u_axis, v_axis)`` of the plane normal to ``axis``."""
    if axis not in (0, 1, 2):
        raise SliceError(f"a slice axis is 0, 1 or 2, not {axis!r}")
    u, v = (a for a in range(3) if a != axis)
    return u, v


@dataclass(frozen=True, eq=False)
class SliceGrid:
    """The sample points of one slice.

    Attributes
    ----------
    axis : int, the axis normal to the slice
    position : float, the world coordinate of the slice along ``axis``
    us : (nu,) world coordinates along ``in_plane_axes(axis)[0]``
    vs : (nv,) world coordinates along ``in_plane_axes(axis)[1]``
    """

    axis: int
    position: float
    us: np.ndarray
    vs: np.ndarray

    @property
    def axes(self) -> tuple[int, int]:
        return in_plane_axes(self.axis)

    @property
    def spacing(self) -> tuple[float, float]:
        """Distance of neighbouring samples along u and v."""
        du = self.us[1] - self.us[0] if len(self.us) > 1 else 1.0
        dv = self.vs[1] - self.vs[0] if len(self.vs) > 1 else 1.0
        return float(du), float(dv)

    def points(self) -> np.ndarray:
        """``(nv, nu, 3)`` world points of the samples."""
        ua, va = self.axes
        p = np.empty((len(self.vs), len(self.us), 3))
        p[..., self.axis] = self.position
        p[..., ua] = self.us[None, :]
        p[..., va] = self.vs[:, None]
        return p

    def to_world(self, uv) -> np.ndarray:
        """``(N, 2)`` plane coordinates -> ``(N, 3)`` world points on the slice."""
        uv = np.atleast_2d(np.asarray(uv, dtype=np.float64))
        ua, va = self.axes
        p = np.empty((len(uv), 3))
        p[:, self.axis] = self.position
        p[:, ua] = uv[:, 0]
        p[:, va] = uv[:, 1]
        return p


def slice_grid(bounds, spacing, axis: int, position: float, oversample: int = 2) -> SliceGrid:
    """The sample grid of the slice ``x[axis] = position`` of a data box.

    Parameters
    ----------
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
    spacing : (3,) the data grid's steps
    axis : int
    position : float, clamped into the box
    oversample : int
        Samples per data grid step along each in-plane axis (fewer when the slice would
        exceed :data:`MAX_SLICE_SAMPLES`).

    Returns
    -------
    SliceGrid
    """
    ua, va = in_plane_axes(axis)
    b = np.asarray(bounds, dtype=np.float64)
    steps = np.asarray(spacing, dtype=np.float64)
    n = [max(int(round((b[a, 1] - b[a, 0]) / steps[a])) * int(oversample) + 1, 1)
         for a in (ua, va)]
    while n[0] * n[1] > MAX_SLICE_SAMPLES:
        n = [max((k + 1) // 2, 2) for k in n]
    us = np.linspace(b[ua, 0], b[ua, 1], n[0])
    vs = np.linspace(b[va, 0], b[va, 1], n[1])
    pos = float(np.clip(position, b[axis, 0], b[axis, 1]))
    return SliceGrid(axis, pos, us, vs)


def sample_slice(spline, grid: SliceGrid) -> np.ndarray:
    """The spline's values ``(nv, nu)`` float64 on a slice grid."""
    pts = grid.points()
    return np.asarray(spline.evaluate(pts.reshape(-1, 3)), dtype=np.float64).reshape(
        pts.shape[:2])


def slice_contours(spline, iso: float, axis: int, position: float) -> list:
    """The exact contour of the isosurface ``s = iso`` on the slice ``x[axis] = position``:
    the cross-section curves of :func:`splineviz.core.sections.plane_section` with that
    plane (the curves a clip plane at the slice shows in the 3-D view).

    Returns
    -------
    list of :class:`~splineviz.core.sections.SectionCurve`
    """
    in_plane_axes(axis)
    b = np.asarray(spline.bounds, dtype=np.float64)
    normal = np.zeros(3)
    normal[axis] = 1.0
    origin = b.mean(axis=1)
    origin[axis] = float(np.clip(position, b[axis, 0], b[axis, 1]))
    return sections.plane_section(spline, iso, origin, normal)


@dataclass(frozen=True)
class Probe:
    """What the probe reads at a point: the spline's value and exact gradient.

    Attributes
    ----------
    position : (3,) world point
    value : float
    gradient : (3,) world-unit gradient
    """

    position: np.ndarray
    value: float
    gradient: np.ndarray

    def describe(self, unit: str = "") -> str:
        """One line for a status bar; ``unit`` (the world coordinates', ``""`` for none)
        follows the position, and the gradient is per that unit."""
        x, y, z = self.position
        gx, gy, gz = self.gradient
        u = f" {unit}" if unit else ""
        per = f" /{unit}" if unit else ""
        return (f"({x:.4g}, {y:.4g}, {z:.4g}){u}  value {self.value:.5g}  "
                f"gradient ({gx:.4g}, {gy:.4g}, {gz:.4g}){per}, |g| "
                f"{float(np.linalg.norm(self.gradient)):.4g}{per}")


def probe(spline, point) -> Probe:
    """Value and gradient of the spline at a world point (clamped into its box)."""
    b = np.asarray(spline.bounds, dtype=np.float64)
    p = np.clip(np.asarray(point, dtype=np.float64).reshape(3), b[:, 0], b[:, 1])
    value, gradient = spline.value_gradient(p[None])
    return Probe(p, float(np.asarray(value)[0]), np.asarray(gradient, dtype=np.float64)[0])
