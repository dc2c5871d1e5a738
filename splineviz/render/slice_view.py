"""VTK props of a 2-D slice view and the slice planes' marker in the 3-D view (no Qt).

:class:`SliceScene` draws one slice (:mod:`splineviz.core.slice_sampling`) into a VTK
renderer in the slice's own frame: the view's x and y are the slice's plane coordinates
``(u, v)`` (world coordinates along its in-plane axes), seen by a parallel camera. It shows
the spline-sampled image through a lookup table spanning ``level -+ window / 2``, the
exact isosurface contours as lines, the crosshair as the traces of the two other slice
planes, a ruler and the slice's name and position.

:class:`SlicePlanesMarker` shows the slice planes in the 3-D view: the outline of each shown
slice where it cuts the data box, in the slice's colour (3D Slicer's colours: axial red,
coronal green, sagittal yellow), and the crosshair point.

Conventions: world coordinates; contour curves are ``(M, 3)`` world vertices (the curves of
:func:`splineviz.core.sections.plane_section`); colours RGB in [0, 1].
"""

from __future__ import annotations

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkLookupTable, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkImageData, vtkPolyData
from vtkmodules.vtkRenderingCore import (
    vtkActor,
    vtkImageProperty,
    vtkImageSlice,
    vtkImageSliceMapper,
    vtkPolyDataMapper,
    vtkTextActor,
)

from splineviz.core.frame import to_world
from splineviz.core.slice_sampling import SliceGrid, in_plane_axes
from splineviz.core.units import format_quantity
from splineviz.render.colormaps import LUT_SIZE, lut

#: slice name -> its colour (3D Slicer's)
SLICE_COLORS = {"axial": (0.95, 0.33, 0.33), "coronal": (0.44, 0.82, 0.4),
                "sagittal": (0.93, 0.84, 0.3)}
#: slice name -> the axis normal to it (as :data:`splineviz.model.slices.AXES`)
SLICE_AXES = {"axial": 2, "coronal": 1, "sagittal": 0}
#: the props' heights above the image, in units of the slice's extent: the contour and the
#: crosshair are drawn over the image, not into it
_LIFT = 1e-3
#: colour of the ruler and its label
RULER_COLOR = (0.3, 0.85, 0.95)


def _polylines(polylines, z: float, colors=None) -> vtkPolyData:
    """Lines through ``(M, 2)`` point lists at height ``z``; ``colors``: one RGB per line."""
    pts, conn, offsets, cell_rgb = [], [], [0], []
    n = 0
    for k, line in enumerate(polylines):
        line = np.asarray(line, dtype=np.float64)
        if len(line) < 2:
            continue
        pts.append(np.column_stack([line, np.full(len(line), z)]))
        conn.append(np.arange(n, n + len(line)))
        n += len(line)
        offsets.append(n)
        if colors is not None:
            cell_rgb.append(colors[k])
    poly = vtkPolyData()
    points = vtkPoints()
    if pts:
        points.SetData(numpy_to_vtk(np.concatenate(pts), deep=True))
    poly.SetPoints(points)
    cells = vtkCellArray()
    if conn:
        cells.SetData(numpy_to_vtkIdTypeArray(np.asarray(offsets, dtype=np.int64), deep=True),
                      numpy_to_vtkIdTypeArray(np.concatenate(conn).astype(np.int64),
                                              deep=True))
    poly.SetLines(cells)
    if cell_rgb:
        rgb = numpy_to_vtk(np.rint(np.asarray(cell_rgb) * 255).astype(np.uint8), deep=True)
        rgb.SetName("colors")
        poly.GetCellData().SetScalars(rgb)
    return poly


def _line_actor(width: float, color=None) -> tuple[vtkActor, vtkPolyDataMapper]:
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(vtkPolyData())
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetLineWidth(width)
    prop.SetLighting(False)
    if color is not None:
        prop.SetColor(*color)
        mapper.ScalarVisibilityOff()
    else:
        mapper.SetColorModeToDirectScalars()
        mapper.SetScalarModeToUseCellData()
    actor.PickableOff()
    return actor, mapper


def vtk_lookup_table(name: str) -> vtkLookupTable:
    """A VTK lookup table of the matplotlib colour map ``name``."""
    table = vtkLookupTable()
    table.SetNumberOfTableValues(LUT_SIZE)
    rgb = lut(name) / 255.0
    for i, (r, g, b) in enumerate(rgb):
        table.SetTableValue(i, float(r), float(g), float(b), 1.0)
    table.Build()
    return table


class SliceScene:
    """The props of one slice view in a VTK renderer (see module docstring).

    Parameters
    ----------
    renderer : vtkRenderer
    name : "axial", "coronal" or "sagittal"
    """

    def __init__(self, renderer, name: str):
        self.renderer = renderer
        self.name = name
        self.axis = SLICE_AXES[name]
        self.axes = in_plane_axes(self.axis)
        #: the slice shown (None before the first image)
        self.grid: SliceGrid | None = None
        #: the contour curves shown, as ``(M, 2)`` plane coordinates per curve
        self.contours: list[np.ndarray] = []
        #: the crosshair's plane coordinates ``(u, v)`` and world point (None before one)
        self.crosshair: tuple | None = None
        self._point: np.ndarray | None = None
        self._extent = np.array([[0.0, 1.0], [0.0, 1.0]])
        self._image = vtkImageData()
        self._mapper = vtkImageSliceMapper()
        self._mapper.SetInputData(self._image)
        self.image_property = vtkImageProperty()
        self.image_property.SetInterpolationTypeToLinear()
        self.image_property.UseLookupTableScalarRangeOff()
        self._slice = vtkImageSlice()
        self._slice.SetMapper(self._mapper)
        self._slice.SetProperty(self.image_property)
        self._slice.VisibilityOff()
        self.color_map = ""
        self._contour_actor, self._contour_mapper = _line_actor(2.5)
        self._cross_actor, self._cross_mapper = _line_actor(1.0)
        self._ruler_actor, self._ruler_mapper = _line_actor(2.0, RULER_COLOR)
        self._ruler_actor.VisibilityOff()
        self.ruler: np.ndarray | None = None
        self._label = vtkTextActor()
        self._label.GetTextProperty().SetColor(*SLICE_COLORS[name])
        self._label.GetTextProperty().SetFontSize(14)
        self._label.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        self._label.SetPosition(0.01, 0.95)
        self._label.GetTextProperty().SetVerticalJustificationToTop()
        self._ruler_label = vtkTextActor()
        self._ruler_label.GetTextProperty().SetColor(*RULER_COLOR)
        self._ruler_label.GetTextProperty().SetFontSize(14)
        self._ruler_label.GetPositionCoordinate().SetCoordinateSystemToWorld()
        self._ruler_label.VisibilityOff()
        for text in (self._label, self._ruler_label):
            # readable over a bright image too
            text.GetTextProperty().SetBackgroundColor(0.0, 0.0, 0.0)
            text.GetTextProperty().SetBackgroundOpacity(0.55)
        for prop in (self._slice, self._contour_actor, self._cross_actor, self._ruler_actor):
            renderer.AddViewProp(prop)
        renderer.AddViewProp(self._label)
        renderer.AddViewProp(self._ruler_label)
        cam = renderer.GetActiveCamera()
        cam.ParallelProjectionOn()
        cam.SetViewUp(0.0, 1.0, 0.0)

    # -- contents ------------------------------------------------------------------------

    def set_extent(self, bounds) -> None:
        """The data box ``((xmin, xmax), (ymin, ymax), (zmin, zmax))`` the slice cuts."""
        b = np.asarray(bounds, dtype=np.float64)
        self._extent = b[list(self.axes)]

    def set_image(self, grid: SliceGrid, values: np.ndarray) -> None:
        """Show the ``(nv, nu)`` samples of ``grid``."""
        self.grid = grid
        nv, nu = values.shape
        du, dv = grid.spacing
        image = vtkImageData()
        image.SetDimensions(nu, nv, 1)
        image.SetSpacing(du, dv, 1.0)
        image.SetOrigin(float(grid.us[0]), float(grid.vs[0]), 0.0)
        scalars = numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float32).ravel(),
                               deep=True)
        scalars.SetName("values")
        image.GetPointData().SetScalars(scalars)
        self._image = image
        self._mapper.SetInputData(image)
        self._slice.VisibilityOn()
        self._update_label()

    def set_window_level(self, window: float, level: float, color_map: str) -> None:
        """Values ``level -+ window / 2`` span the colour map ``color_map``."""
        if color_map != self.color_map:
            self.image_property.SetLookupTable(vtk_lookup_table(color_map))
            self.color_map = color_map
        self.image_property.SetColorWindow(float(window))
        self.image_property.SetColorLevel(float(level))

    def set_contours(self, curves, colors) -> None:
        """Show the contour ``curves`` (SectionCurve or ``(M, 3)`` world vertices; a closed
        curve is drawn back to its first vertex), one RGB colour per curve."""
        lines, rgb = [], []
        ua, va = self.axes
        for curve, color in zip(curves, colors, strict=True):
            pts = np.asarray(getattr(curve, "points", curve), dtype=np.float64)
            if getattr(curve, "closed", False) and len(pts) > 2:
                pts = np.vstack([pts, pts[:1]])
            lines.append(pts[:, [ua, va]])
            rgb.append(color)
        self.contours = lines
        self._contour_mapper.SetInputData(_polylines(lines, self._lift(1), rgb))

    def set_crosshair(self, point) -> None:
        """The traces of the two other slice planes through the world ``point``."""
        ua, va = self.axes
        (u0, u1), (v0, v1) = self._extent
        cu, cv = float(point[ua]), float(point[va])
        # the vertical line is the plane normal to the u axis, the horizontal one to v's
        names = {a: n for n, a in SLICE_AXES.items()}
        lines = [np.array([[cu, v0], [cu, v1]]), np.array([[u0, cv], [u1, cv]])]
        colors = [SLICE_COLORS[names[ua]], SLICE_COLORS[names[va]]]
        self._cross_mapper.SetInputData(_polylines(lines, self._lift(2), colors))
        self.crosshair = (cu, cv)
        self._point = np.asarray(point, dtype=np.float64)
        self._update_label()

    def set_ruler(self, a, b, unit: str = "") -> None:
        """A ruler between the world points ``a`` and ``b`` (None: no ruler), labelled with
        its length in world units (``unit``: the volume's, see :mod:`splineviz.core.units`)."""
        if a is None or b is None:
            self.ruler = None
            self._ruler_actor.VisibilityOff()
            self._ruler_label.VisibilityOff()
            return
        a = np.asarray(a, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        self.ruler = np.stack([a, b])
        ua, va = self.axes
        uv = self.ruler[:, [ua, va]]
        self._ruler_mapper.SetInputData(_polylines([uv], self._lift(3)))
        self._ruler_actor.VisibilityOn()
        length = float(np.linalg.norm(b - a))
        self._ruler_label.SetInput(format_quantity(length, unit, ascii=True))
        mid = uv.mean(axis=0)
        self._ruler_label.SetPosition(float(mid[0]), float(mid[1]))
        self._ruler_label.VisibilityOn()

    def _lift(self, level: int) -> float:
        span = float(np.max(self._extent[:, 1] - self._extent[:, 0])) or 1.0
        return level * _LIFT * span

    def _update_label(self) -> None:
        point = self._point
        if point is None:
            return
        axis_name = "xyz"[self.axis]
        self._label.SetInput(f"{self.name.capitalize()}  {axis_name} = "
                             f"{point[self.axis]:.4g}")

    # -- camera and picking --------------------------------------------------------------

    def reset_camera(self, aspect: float) -> None:
        """Fit the slice's extent into a view of width / height ``aspect``."""
        (u0, u1), (v0, v1) = self._extent
        cu, cv = 0.5 * (u0 + u1), 0.5 * (v0 + v1)
        half_h = 0.5 * max(v1 - v0, (u1 - u0) / max(aspect, 1e-6))
        cam = self.renderer.GetActiveCamera()
        span = max(u1 - u0, v1 - v0, 1e-12)
        cam.SetFocalPoint(cu, cv, 0.0)
        cam.SetPosition(cu, cv, 2.0 * span)
        cam.SetViewUp(0.0, 1.0, 0.0)
        cam.SetParallelScale(1.04 * half_h)
        self.renderer.ResetCameraClippingRange()

    def zoom(self, factor: float) -> None:
        """Zoom the view by ``factor`` (> 1: closer)."""
        cam = self.renderer.GetActiveCamera()
        cam.SetParallelScale(cam.GetParallelScale() / factor)

    def display_to_plane(self, x: float, y: float) -> np.ndarray:
        """Plane coordinates ``(2,)`` of the display pixel (x, y) (VTK's: y up)."""
        r = self.renderer
        r.SetDisplayPoint(float(x), float(y), 0.0)
        r.DisplayToWorld()
        w = np.asarray(r.GetWorldPoint(), dtype=np.float64)
        return w[:2] / (w[3] if w[3] else 1.0)

    def plane_to_display(self, uv) -> np.ndarray:
        """Display pixel ``(2,)`` (VTK's: y up) of plane coordinates ``(u, v)``."""
        r = self.renderer
        r.SetWorldPoint(float(uv[0]), float(uv[1]), 0.0, 1.0)
        r.WorldToDisplay()
        return np.asarray(r.GetDisplayPoint()[:2], dtype=np.float64)

    def to_world(self, uv, position: float) -> np.ndarray:
        """World point ``(3,)`` of plane coordinates ``uv`` on the slice at ``position``."""
        p = np.empty(3)
        p[self.axis] = position
        p[list(self.axes)] = uv
        return p


class SlicePlanesMarker:
    """The slice planes and the crosshair point in the 3-D views (see module docstring).

    Each 3-D view (both halves of a split view) has its own actors over the same lines:
    VTK props are not shared between render windows (each has its own OpenGL context).

    Parameters
    ----------
    renderer : vtkRenderer of the 3-D view
    """

    def __init__(self, renderer):
        self.renderer = renderer
        #: the outlines shown: slice name -> (5, 3) world points (closed rectangle)
        self.outlines: dict[str, np.ndarray] = {}
        self._lines = _polylines3([], [])
        self._ruler_lines = _polylines3([], [])
        #: the ruler's ends ``(2, 3)`` (world) while one is shown
        self.ruler: np.ndarray | None = None
        self._ruler_text = ""
        self._ruler_mid = (0.0, 0.0, 0.0)
        #: the volume whose own frame the slice views work in: their points are drawn
        #: turned into world by its direction (an oblique scan); None: world itself
        self.frame = None
        #: renderer -> (outline actor, ruler actor, ruler label) drawn in it
        self._props: dict = {}
        self.add_renderer(renderer)

    @property
    def renderers(self) -> list:
        """The renderers the marker draws in (the first 3-D view's first)."""
        return list(self._props)

    def add_renderer(self, renderer) -> None:
        """Draw the marker in ``renderer`` too (the second view of a split)."""
        if renderer in self._props:
            return
        actor, mapper = _line_actor(2.0)
        mapper.SetInputData(self._lines)
        actor.SetVisibility(bool(self.outlines))
        renderer.AddActor(actor)
        ruler, ruler_mapper = _line_actor(3.0, RULER_COLOR)
        ruler_mapper.SetInputData(self._ruler_lines)
        renderer.AddActor(ruler)
        label = vtkTextActor()
        prop = label.GetTextProperty()
        prop.SetColor(*RULER_COLOR)
        prop.SetFontSize(14)
        prop.SetBackgroundColor(0.0, 0.0, 0.0)
        prop.SetBackgroundOpacity(0.55)
        label.GetPositionCoordinate().SetCoordinateSystemToWorld()
        renderer.AddViewProp(label)
        self._props[renderer] = (actor, ruler, label)
        self._show_ruler(renderer)

    def remove_renderer(self, renderer) -> None:
        """Stop drawing in ``renderer`` (a closed view)."""
        props = self._props.pop(renderer, None)
        if props is not None:
            actor, ruler, label = props
            renderer.RemoveActor(actor)
            renderer.RemoveActor(ruler)
            renderer.RemoveViewProp(label)

    def _show_ruler(self, renderer) -> None:
        _actor, ruler, label = self._props[renderer]
        shown = self.ruler is not None and bool(np.any(self.ruler[0] != self.ruler[1]))
        ruler.SetVisibility(shown)
        label.SetInput(self._ruler_text)
        label.GetPositionCoordinate().SetValue(*self._ruler_mid)
        label.SetVisibility(shown)

    def set_ruler(self, a, b, unit: str = "") -> None:
        """A ruler between the world points ``a`` and ``b`` labelled with its length in
        ``unit`` (``a`` None: no ruler)."""
        if a is None:
            self.ruler = None
        else:
            a = np.asarray(a, dtype=np.float64)
            b = a if b is None else np.asarray(b, dtype=np.float64)
            self.ruler = np.stack([a, b])
            self._ruler_lines.DeepCopy(_polylines3([to_world(self.frame, self.ruler)],
                                                   [RULER_COLOR]))
            self._ruler_text = format_quantity(float(np.linalg.norm(b - a)), unit, ascii=True)
            self._ruler_mid = tuple(map(float, to_world(self.frame, 0.5 * (a + b))))
        for renderer in self._props:
            self._show_ruler(renderer)

    def update(self, bounds, point, names) -> None:
        """Outline the slices ``names`` through ``point`` within the box ``bounds`` (no
        names: nothing shown); both in the slice views' frame (:attr:`frame`), the
        outlines in world."""
        b = np.asarray(bounds, dtype=np.float64)
        self.outlines = {}
        segments, colors = [], []
        for name in names:
            axis = SLICE_AXES[name]
            ua, va = in_plane_axes(axis)
            corners = np.empty((5, 3))
            corners[:, axis] = point[axis]
            for k, (i, j) in enumerate(((0, 0), (1, 0), (1, 1), (0, 1), (0, 0))):
                corners[k, ua] = b[ua, i]
                corners[k, va] = b[va, j]
            corners = to_world(self.frame, corners)
            self.outlines[name] = corners
            segments.append(corners)
            colors.append(SLICE_COLORS[name])
        self._lines.DeepCopy(_polylines3(segments, colors))
        for actor, _ruler, _label in self._props.values():
            actor.SetVisibility(bool(segments))

    def close(self) -> None:
        for renderer in list(self._props):
            self.remove_renderer(renderer)


def _polylines3(lines, colors) -> vtkPolyData:
    """Lines through ``(M, 3)`` world points, one RGB colour per line."""
    flat = [np.asarray(line)[:, :2] for line in lines]
    poly = _polylines(flat, 0.0, colors)
    if lines:
        poly.GetPoints().SetData(numpy_to_vtk(np.concatenate(lines).astype(np.float64),
                                              deep=True))
    return poly
