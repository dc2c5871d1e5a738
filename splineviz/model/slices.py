"""The state of the 2-D slice views (no Qt, no VTK): layout, crosshair, window / level.

The slice views (3D Slicer's axial, coronal and sagittal views beside the 3-D view) show one
volume of the scene cut by three axis-aligned planes through one point, the *crosshair*. A
click in a slice view moves the crosshair within that view's plane; the wheel moves it along
the view's normal by one grid step of the volume. Every slice view and the 3-D view follow
:class:`SliceViewNode`, so moving the crosshair in one moves the planes of the others.

The node is view state like :class:`~splineviz.model.nodes.CameraNode`: it is not one of
the scene's objects. Sessions keep its layout and crosshair through the scene's
:class:`~splineviz.model.nodes.ViewNode` (``slice_layout``, ``slice_single``,
``crosshair``), which the GUI's slice views follow and update.

Conventions: world coordinates; axis 0, 1, 2 is x, y, z; the slice named ``"sagittal"``
is normal to x, ``"coronal"`` to y and ``"axial"`` to z (a patient lying along z, as in
DICOM's patient coordinates). A slice view shows its plane with the first of its two
in-plane axes (:data:`IN_PLANE`) to the right and the second up.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from splineviz.model.nodes import LAYOUTS, Finite, Node, SliceName, Vec3

#: slice name -> the axis normal to it
AXES = {"axial": 2, "coronal": 1, "sagittal": 0}
#: slice name -> (axis shown to the right, axis shown up)
IN_PLANE = {"axial": (0, 1), "coronal": (0, 2), "sagittal": (1, 2)}
#: colour maps offered for the slice image (matplotlib names)
SLICE_COLORMAPS = ("gray", "bone", "viridis", "inferno", "magma", "cividis")


class SliceViewNode(Node):
    """Layout and shared state of the slice views (see module docstring).

    Attributes
    ----------
    layout : one of :data:`LAYOUTS`
    single : the slice shown by the ``"one-slice"`` layout
    volume_id : the volume shown (None: the volume of the selected or first isosurface)
    crosshair : (3,) world point where the three slice planes meet
    window, level : the value range ``level -+ window / 2`` spans the colour map
    color_map : one of :data:`SLICE_COLORMAPS`
    """

    kind: str = Field(default="slices", exclude=True, frozen=True)
    layout: Literal[LAYOUTS] = "3d"
    single: SliceName = "axial"
    volume_id: str | None = None
    crosshair: Vec3 = (0.0, 0.0, 0.0)
    window: Annotated[float, Field(gt=0.0, le=1e300, allow_inf_nan=False)] = 1.0
    level: Finite = 0.5
    color_map: Literal[SLICE_COLORMAPS] = "gray"

    @property
    def shown(self) -> tuple[str, ...]:
        """The slices the current layout shows."""
        if self.layout == "four-up":
            return ("axial", "coronal", "sagittal")
        if self.layout == "one-slice":
            return (self.single,)
        return ()

    def position(self, name: str) -> float:
        """World coordinate of slice ``name`` along its normal axis."""
        return float(self.crosshair[AXES[name]])

    def fit(self, volume) -> None:
        """Put the crosshair at the centre sample of ``volume`` and the window on its
        value range (2-98 % of the samples: a few extreme voxels do not grey the rest)."""
        centre = np.asarray(volume.shape) // 2
        point = volume.index_to_world(centre[None].astype(np.float64))[0]
        data = np.asarray(volume.data)
        finite = data[np.isfinite(data)] if data.dtype.kind == "f" else data.ravel()
        lo, hi = (np.percentile(finite[::max(1, finite.size // 1_000_000)], (2.0, 98.0))
                  if finite.size else (0.0, 1.0))
        if not hi > lo:
            lo, hi = volume.finite_range
        if not hi > lo:
            hi = lo + 1.0
        self.update(crosshair=tuple(map(float, point)), window=float(hi - lo),
                    level=float(0.5 * (lo + hi)))

    def move_to(self, point, volume) -> None:
        """Move the crosshair to a world point, kept inside ``volume``'s box."""
        lo, hi = np.asarray(volume.bounds, dtype=np.float64).T
        p = np.clip(np.asarray(point, dtype=np.float64), lo, hi)
        self.crosshair = tuple(map(float, p))

    def scroll(self, name: str, steps: int, volume) -> None:
        """Move slice ``name`` by ``steps`` grid steps of ``volume`` along its normal; the
        slice lands on a grid plane and stays inside the volume."""
        axis = AXES[name]
        origin, spacing = volume.origin[axis], volume.spacing[axis]
        index = round((self.crosshair[axis] - origin) / spacing) + int(steps)
        index = min(max(index, 0), volume.shape[axis] - 1)
        point = list(self.crosshair)
        point[axis] = float(origin + index * spacing)
        self.crosshair = tuple(point)

    def index(self, name: str, volume) -> float:
        """Slice ``name``'s position as a (fractional) grid index of ``volume``."""
        axis = AXES[name]
        return (self.crosshair[axis] - volume.origin[axis]) / volume.spacing[axis]
