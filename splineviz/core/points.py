"""The point-cloud data model: (N, 3) float64 positions with optional (N, 3) normals."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splineviz.core.errors import SplinevizError


class PointCloudError(SplinevizError, ValueError):
    """A point set that cannot be used (wrong shape, non-finite values, mismatched normals)."""


@dataclass(frozen=True, eq=False)
class PointCloud:
    """Unorganised points in 3-D.

    Parameters
    ----------
    points : (N, 3) array_like
        Positions; stored as float64. Must be finite.
    normals : (N, 3) array_like, optional
        Normals (not necessarily unit length); stored as float64.
    """

    points: np.ndarray
    normals: np.ndarray | None = None

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise PointCloudError(f"points must have shape (N, 3), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise PointCloudError("points contain NaN or infinite coordinates")
        object.__setattr__(self, "points", np.ascontiguousarray(pts))
        if self.normals is not None:
            nrm = np.asarray(self.normals, dtype=np.float64)
            if nrm.shape != pts.shape:
                raise PointCloudError(
                    f"normals must match points in shape, got {nrm.shape} for {pts.shape}"
                )
            object.__setattr__(self, "normals", np.ascontiguousarray(nrm))

    def __len__(self) -> int:
        return len(self.points)

    @property
    def bounds(self) -> tuple[tuple[float, float], ...]:
        """((xmin, xmax), (ymin, ymax), (zmin, zmax)); raises for an empty cloud."""
        if len(self) == 0:
            raise PointCloudError("an empty point cloud has no bounds")
        lo, hi = self.points.min(axis=0), self.points.max(axis=0)
        return tuple((float(a), float(b)) for a, b in zip(lo, hi, strict=True))

    @property
    def diagonal(self) -> float:
        """Length of the bounding-box diagonal."""
        (x0, x1), (y0, y1), (z0, z1) = self.bounds
        return float(np.linalg.norm([x1 - x0, y1 - y0, z1 - z0]))

    def show(self, size=None, camera=None, **options):
        """The picture of a new scene holding just these points, framed isometric (see
        :func:`splineviz.notebook.show`)."""
        from splineviz.core.pictures import show

        return show(self, size=size, camera=camera, **options)

    def _repr_png_(self) -> bytes:
        """A notebook shows the cloud as :meth:`show`'s picture."""
        return self.show().png()
