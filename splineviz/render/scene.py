"""A VTK scene that shows ray-cast (or cell-projected) spline isosurfaces among ordinary props
(thesis §6.3, §6.1).

:class:`SplineScene` wraps a pyvista plotter (an off-screen ``pyvista.Plotter`` or the Qt
``QtInteractor``). Before every render (the renderer's ``StartEvent``) it

1. resets the camera clipping range over the visible props (the isosurface quads report the
   data box as their bounds),
2. compares each visible layer's shown frame with what the view needs now (camera, clipping
   range, window size, clip planes, layer state) and, if it differs, ray casts a new one,
3. orders the quads after all other props, opaque layers first and translucent ones back to
   front, so a translucent surface blends over the meshes already drawn and is hidden where a
   mesh is nearer (its fragments fail the depth test),
4. previews the volume renderings (:class:`~splineviz.render.volume_layer.VolumeLayer`) it
   can cast within the budget; after the scene's pass (``EndEvent``) it reads the window
   depth their rays end at, and their images are drawn over the picture by an overlay
   renderer (window layer 1), as ``render_scene`` composites them.

A layer drawn by cell projection (:meth:`IsosurfaceLayer.renderer_choice`) casts no frame:
its tets (made in step 2 for a picture, by :meth:`refine` in a worker for the GUI) are drawn
by its :class:`~splineviz.render.cell_projection.CellProjectionLayer` actors, which write
their depth per fragment as the quads do and are ordered with them in step 3.

Modes: ``progressive=False`` (scripts, screenshots) casts exact frames synchronously at full
size. ``progressive=True`` (the GUI) casts a reduced-resolution preview synchronously, sized
to a time budget, and calls :attr:`SplineScene.request_refine` so that the owner can compute
the exact frames in a worker thread (:meth:`refine`) and show them (:meth:`apply`).

The scene also keeps what it shows (meshes, point clouds, outline) as data plus display
options, so :func:`offscreen_screenshot` can rebuild it in an off-screen window of any size.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from splineviz.core.camera import Camera
from splineviz.core.errors import SplinevizError
from splineviz.core.frame import world_bounds
from splineviz.core.raycast_reference import normalize_clip_planes
from splineviz.core.renderers import CELL_PROJECTION, RAY_CASTING
from splineviz.render.colormaps import colorize, lut
from splineviz.render.colour_ranges import ColourRangeLink, FixedRanges, range_key
from splineviz.render.isosurface import IsosurfaceLayer, RenderedFrame, ViewState
from splineviz.render.quad import FrameQuad, frame_colors, frame_textures
from splineviz.render.volume_layer import VolumeFrame, VolumeLayer, depth_signature

#: seconds a synchronous preview may take in the GUI thread, from the cast to its uploaded
#: textures (keeps the window responsive while dragging)
PREVIEW_BUDGET_S = 0.045
#: smallest preview resolution factor
MIN_PREVIEW_SCALE = 1.0 / 16.0
#: the resolution factors a preview may use (powers of sqrt 2 from 1 down to
#: :data:`MIN_PREVIEW_SCALE`). The OpenCL device (PoCL) compiles the ray-cast kernel anew for
#: each new frame size (0.2-0.7 s measured on 2 cores); a continuous scale made almost every
#: drag step a new size and stalled the window for that long. With these few levels each
#: size of a window is compiled once (and PoCL keeps it in its disk cache).
PREVIEW_LEVELS = tuple(2.0 ** (-k / 2.0) for k in range(9))
#: the first preview's resolution factor of an isosurface and of a volume rendering (a ray
#: of a volume rendering integrates the whole volume: its first previews at 1/4 took 110-210
#: ms on 2 cores, at 1/8 about 20 ms; the budget then grows the scale)
FIRST_PREVIEW_SCALE = 0.25
FIRST_VOLUME_PREVIEW_SCALE = 0.125
#: windows narrower than this many pixels get scalar bars with fewer labels across more width
NARROW_BAR_PX = 480
#: pixels of height of a scalar bar: the colour bar, its labels and its title above them
BAR_HEIGHT_PX = 46


class SceneError(SplinevizError, ValueError):
    """Bad scene request (unknown object, bad screenshot size)."""


@dataclass
class PropRecord:
    """An ordinary prop of the scene: its data and ``add_mesh`` options (for re-creation)."""

    name: str
    dataset: object
    options: dict
    actor: object
    kind: str = "mesh"
    visible: bool = True


@dataclass
class _LayerView:
    quad: FrameQuad
    shown: RenderedFrame | None = None
    mean_depth: float = 1.0
    preview_scale: float | None = None
    #: preview frame sizes cast so far; seconds of the last preview (None: none yet, or
    #: one of a new size, whose time includes compiling the kernel for that size)
    preview_sizes: set = field(default_factory=set)
    preview_seconds: float | None = None
    callback: object = None
    pending: dict = field(default_factory=dict)
    #: the colour-by legend of this layer (a vtkScalarBarActor, shown while colouring by)
    scalar_bar: object = None
    #: the (lo, hi) the colour map spans in the shown frame
    color_range: tuple | None = None
    #: the layer's cell-projection actors in this view (None: not drawn so yet), and
    #: whether they draw it now (its quad is hidden then)
    cells: object = None
    by_cells: bool = False
    #: whether its cell-projected frames are drawn off the GUI thread and shown by its quad
    #: (a frame takes longer than the preview budget) instead of by its actors in the window
    cell_frames: bool = False
    #: its stand-in mesh while the camera moves (a ProxySurface, None: none yet), and
    #: whether it shows instead of the cell-projection actors or frame now
    proxy: object = None
    proxy_shown: bool = False


@dataclass
class _VolumeView:
    """The overlay image of a :class:`VolumeLayer` and its preview bookkeeping (the fields
    :meth:`SplineScene._preview_scale` reads)."""

    actor: object
    image: object
    shown: VolumeFrame | None = None
    preview_scale: float | None = None
    preview_sizes: set = field(default_factory=set)
    preview_seconds: float | None = None


def view_state_of(renderer, size, clip_planes=()) -> ViewState:
    """The :class:`ViewState` of a VTK renderer's active camera at ``size`` (width, height)."""
    cam = renderer.GetActiveCamera()
    if cam.GetParallelProjection():
        cam.ParallelProjectionOff()  # the ray caster is perspective only
    camera = Camera(cam.GetPosition(), cam.GetFocalPoint(), cam.GetViewUp(), cam.GetViewAngle(),
                    clipping_range=cam.GetClippingRange())
    planes = tuple(tuple(map(tuple, p)) for p in normalize_clip_planes(clip_planes))
    return ViewState(camera, (int(size[0]), int(size[1])), planes)


class SplineScene:
    """Spline isosurfaces and ordinary props in one pyvista plotter (see module docstring).

    Parameters
    ----------
    plotter : pyvista.Plotter or pyvistaqt.QtInteractor
    progressive : bool
        Preview + :attr:`request_refine` instead of synchronous exact frames.
    """

    def __init__(self, plotter, progressive: bool = False):
        self.plotter = plotter
        self.renderer = plotter.renderer
        self.progressive = progressive
        #: called with no argument when exact frames are due (progressive mode)
        self.request_refine = None
        #: key of the view the last render was for (a refining worker compares its own)
        self._latest_key = None
        self.layers: list[IsosurfaceLayer] = []
        self._views: dict[int, _LayerView] = {}
        self.props: dict[str, PropRecord] = {}
        self._clip_planes: list = []
        self._interacting = False
        self._force_exact = False
        #: the window was resized since the last render (:meth:`view_resized`)
        self._resized = False
        self.last_frame_s = None
        self.frame_times: list[float] = []
        #: the finest preview resolution factor (the preview quality the GUI's preferences
        #: set: 1 lets a fast preview reach full resolution)
        self.max_preview_scale = 1.0
        #: the :class:`ColourRangeLink` of the views of this scene's model (None: alone;
        #: a :class:`FixedRanges` for a copy in another window)
        self.range_link: ColourRangeLink | FixedRanges | None = None
        #: called with no argument when the picture changed outside a render (a linked
        #: view changed a shared colour range); the owner renders soon after
        self.request_render = None
        #: volume renderings (:class:`VolumeLayer`), drawn over the picture in an overlay
        #: renderer (created with the first)
        self.volume_layers: list[VolumeLayer] = []
        self._vviews: dict[int, _VolumeView] = {}
        self._overlay = None
        #: (view key, (H, W) window depth, signature) of the last render, read while a
        #: volume layer is visible
        self._depth = None
        self._observer = self.renderer.AddObserver("StartEvent", self._before_render)
        self._end_observer = self.renderer.AddObserver("EndEvent", self._after_render)
        #: seconds of the last window frame that drew a surface by cell projection (its
        #: GL work happens by the window's end, not the renderer's), or of the last
        #: cell-projected frame a worker drew for it (see :meth:`cells_fast`)
        self.cells_seconds: float | None = None
        self._cells_drawn = False
        self._t_window = None
        rw = plotter.render_window
        self._window_observers = (rw.AddObserver("StartEvent", self._window_started),
                                  rw.AddObserver("EndEvent", self._window_ended))

    # -- objects -------------------------------------------------------------------------

    def add_layer(self, layer: IsosurfaceLayer) -> None:
        quad = FrameQuad(world_bounds(layer.volume))
        lv = _LayerView(quad)

        def changed(_layer, what, lv=lv):
            self._apply_appearance(_layer, lv)
            if what == "frame":
                lv.quad.set_bounds(world_bounds(_layer.volume))

        lv.callback = changed
        layer.connect(changed)
        self.layers.append(layer)
        self._views[id(layer)] = lv
        self.renderer.AddActor(quad.actor)
        lv.scalar_bar = _scalar_bar(len(self.layers) - 1)
        self.renderer.AddActor(lv.scalar_bar)
        self._apply_appearance(layer, lv)

    def remove_layer(self, layer: IsosurfaceLayer) -> None:
        lv = self._views.pop(id(layer), None)
        if lv is None:
            raise SceneError(f"layer {layer.name!r} is not in this scene")
        layer.disconnect(lv.callback)
        self.layers.remove(layer)
        if self.range_link is not None:
            self.range_link.forget(self, range_key(layer))
        self.renderer.RemoveActor(lv.quad.actor)
        self.renderer.RemoveActor(lv.scalar_bar)
        self._drop_cells(lv)

    def add_volume_layer(self, layer: VolumeLayer) -> None:
        """Show ``layer``'s volume rendering over the picture."""
        import vtk

        if self._overlay is None:
            self._overlay = vtk.vtkRenderer()
            self._overlay.SetLayer(1)
            self._overlay.InteractiveOff()
            rw = self.plotter.render_window
            rw.SetNumberOfLayers(max(2, rw.GetNumberOfLayers()))
            rw.AddRenderer(self._overlay)
        image = vtk.vtkImageData()
        mapper = vtk.vtkImageMapper()
        mapper.SetInputData(image)
        mapper.SetColorWindow(255.0)
        mapper.SetColorLevel(127.5)
        actor = vtk.vtkActor2D()
        actor.SetMapper(mapper)
        actor.VisibilityOff()
        self._overlay.AddActor(actor)
        self.volume_layers.append(layer)
        self._vviews[id(layer)] = _VolumeView(actor, image)

    def remove_volume_layer(self, layer: VolumeLayer) -> None:
        vv = self._vviews.pop(id(layer), None)
        if vv is None:
            raise SceneError(f"volume rendering {layer.name!r} is not in this scene")
        self.volume_layers.remove(layer)
        self._overlay.RemoveActor(vv.actor)

    def quad(self, layer: IsosurfaceLayer) -> FrameQuad:
        return self._views[id(layer)].quad

    def shown_frame(self, layer: IsosurfaceLayer) -> RenderedFrame | None:
        """The frame the layer's quad (or a volume layer's overlay) shows now (None before
        the first render)."""
        if isinstance(layer, VolumeLayer):
            return self._vviews[id(layer)].shown
        return self._views[id(layer)].shown

    def add_mesh(self, name: str, dataset, kind: str = "mesh", **options) -> PropRecord:
        """Add a pyvista dataset with ``plotter.add_mesh`` options; replaces ``name``."""
        if name in self.props:
            self.remove_prop(name)
        # render=False: the owner renders when it is ready (pyvista would render at once, and
        # in a window that means a synchronous frame with previews of every layer)
        actor = self.plotter.add_mesh(dataset, name=name, reset_camera=False, render=False,
                                      **options)
        rec = PropRecord(name, dataset, dict(options), actor, kind)
        self.props[name] = rec
        return rec

    def remove_prop(self, name: str) -> None:
        rec = self.props.pop(name, None)
        if rec is None:
            raise SceneError(f"no object named {name!r} in the scene")
        self.plotter.remove_actor(rec.actor, reset_camera=False, render=False)

    def set_prop_visible(self, name: str, visible: bool) -> None:
        rec = self.props[name]
        rec.visible = bool(visible)
        rec.actor.SetVisibility(rec.visible)

    # -- clip planes ---------------------------------------------------------------------

    @property
    def clip_planes(self) -> tuple:
        return tuple(self._clip_planes)

    def set_clip_planes(self, planes) -> None:
        """Clip planes of the isosurfaces: (origin, normal) pairs, each keeps the side its
        normal points to (docs/api.md). Meshes are not clipped: they show what the cut opens."""
        self._clip_planes = [tuple(map(tuple, p)) for p in normalize_clip_planes(planes)]

    # -- rendering -----------------------------------------------------------------------

    def window_size(self) -> tuple[int, int]:
        w, h = self.plotter.render_window.GetSize()
        return max(int(w), 1), max(int(h), 1)

    def view_state(self) -> ViewState:
        return view_state_of(self.renderer, self.window_size(), self._clip_planes)

    def next_view_state(self) -> ViewState:
        """The view the next render is for: the near and far planes reset as a render
        resets them (frames cast in a worker for a render to come must be of this view, or
        that render casts them again)."""
        self._reset_clipping_range()
        return self.view_state()

    def set_interacting(self, flag: bool) -> None:
        """Tell the scene a camera drag is in progress (previews) or over (refine)."""
        self._interacting = bool(flag)

    def view_resized(self) -> None:
        """The view is being resized: its next render casts no preview of the new size for
        a layer whose last frame is of its current state; that frame stays, stale, until
        the exact frame (on software OpenGL a widget resize renders at once, and a layout
        change resizes the view two or three times: a preview in each held the GUI thread
        40-90 ms)."""
        self._resized = True

    def _apply_appearance(self, layer: IsosurfaceLayer, lv: _LayerView) -> None:
        q = lv.quad
        q.set_appearance(layer.color, layer.opacity)
        q.set_material(layer.material)
        q.actor.SetVisibility(bool(layer.visible and q.has_image and not lv.proxy_shown
                                   and (not lv.by_cells or lv.cell_frames)))
        if lv.cells is not None:
            lv.cells.set_appearance(layer.color, layer.opacity)
            lv.cells.set_material(layer.material)
            lv.cells.set_visible(bool(layer.visible and lv.by_cells and not lv.cell_frames
                                      and not lv.proxy_shown))
        if lv.proxy is not None:
            lv.proxy.set_appearance(layer.color, layer.opacity, layer.material)
            lv.proxy.actor.SetVisibility(bool(layer.visible and lv.by_cells
                                              and lv.proxy_shown))
        self._apply_colors(layer, lv)

    def _apply_colors(self, layer: IsosurfaceLayer, lv: _LayerView) -> None:
        """Colour the shown frame by its scalars with the layer's map and range, and update
        the layer's scalar bar (no new ray cast: the scalars are kept with the frame)."""
        rf = lv.shown
        scalars = None if rf is None or layer.color_by == "none" else rf.scalars
        link = self.range_link
        if scalars is None:
            lv.quad.set_colors(None, None)
            lv.color_range = None
            if link is not None:
                link.forget(self, range_key(layer))
        else:
            lo, hi = layer.color_range_of(scalars[rf.frame.hit])
            if link is not None and layer.color_range != "manual":
                lo, hi = link.report(self, range_key(layer), (lo, hi))
            lv.color_range = (lo, hi)
            lv.quad.set_colors(scalars.shape[::-1],
                               frame_colors(colorize(scalars, layer.color_map, lo, hi)))
            _update_scalar_bar(lv.scalar_bar, layer.color_map, lo, hi,
                               f"{layer.name}: {layer.color_by}")
        lv.scalar_bar.SetVisibility(bool(layer.visible and lv.color_range is not None))

    def recolour(self, key) -> None:
        """Colour the shown frame of the surface ``key`` (:func:`range_key`) again: its
        shared range changed in another view of the link."""
        for layer in self.layers:
            if range_key(layer) == key:
                self._apply_colors(layer, self._views[id(layer)])
                if self.request_render is not None:
                    self.request_render()

    def color_range(self, layer: IsosurfaceLayer) -> tuple | None:
        """The ``(lo, hi)`` the layer's colour map spans in the shown frame (None: flat)."""
        return self._views[id(layer)].color_range

    def picked_value(self, layer: IsosurfaceLayer, x: int, y: int) -> float | None:
        """The colour-by value under window pixel ``(x, y)`` (VTK display coordinates,
        origin bottom left) in the shown frame; None where there is no hit or no colouring."""
        lv = self._views[id(layer)]
        rf = lv.shown
        if rf is None or rf.scalars is None:
            return None
        w, h = rf.view.size
        fh, fw = rf.scalars.shape
        col = int(np.clip(x * fw / w, 0, fw - 1))
        row = int(np.clip((h - 1 - y) * fh / h, 0, fh - 1))
        value = float(rf.scalars[row, col])
        return value if np.isfinite(value) else None

    # -- cell projection (thesis §6.1) ----------------------------------------------------

    def _drop_cells(self, lv: _LayerView) -> None:
        if lv.cells is not None:
            for actor in lv.cells.actors:
                self.renderer.RemoveActor(actor)
        if lv.proxy is not None:
            self.renderer.RemoveActor(lv.proxy.actor)
        lv.cells = None
        lv.proxy = None
        lv.proxy_shown = False

    def _window_started(self, *_args) -> None:
        self._t_window = time.perf_counter()

    def _window_ended(self, *_args) -> None:
        if self._cells_drawn and self._t_window is not None:
            self.cells_seconds = time.perf_counter() - self._t_window

    def cells_fast(self) -> bool:
        """Whether the last cell-projected frame took at most the preview budget: a
        progressive view then draws cell-projected surfaces in its window at every render,
        else (software OpenGL: 0.25-0.8 s for the default data) their exact frames are drawn
        off the GUI thread (:meth:`IsosurfaceLayer.cell_frame`, in :meth:`refine`) and
        shown by their quads, the trilinear stand-in meanwhile."""
        return self.cells_seconds is not None and self.cells_seconds <= PREVIEW_BUDGET_S

    def _draw_cells(self, layer: IsosurfaceLayer, lv: _LayerView, view: ViewState,
                    blocking: bool) -> bool:
        """Draw ``layer`` by cell projection in this view: its tets of the current
        isovalue (made now when ``blocking``, else the last ones made until a worker made
        those: :meth:`refine`), cut by the view's and the layer's clip planes, by its
        actors or, when not :meth:`cells_fast` in a progressive view, as the frame a worker
        drew. True when what is shown is the current surface, exact."""
        from splineviz.render.cell_projection import CellProjectionLayer

        geometry = layer.cell_geometry(blocking=blocking)
        if geometry is not None and (lv.cells is None
                                     or lv.cells.spline is not geometry.spline):
            self._drop_cells(lv)
            lv.cells = CellProjectionLayer(geometry.spline, None)
            for actor in lv.cells.actors:
                # the near and far planes come from the data box (_reset_clipping_range),
                # as for a ray-cast frame: the tets' own bounds reach half a cell beyond it
                # (type-6 cubes are centred at the samples), and the window depths of the
                # two renderers' pictures would differ by the other clipping range
                actor.SetUseBounds(False)
                self.renderer.AddActor(actor)
        if geometry is not None and lv.cells.geometry is not geometry:
            lv.cells.set_geometry(geometry)
        if not lv.by_cells:
            # the quad's frame is of the ray caster: not shown, nor described, from now on
            lv.by_cells = True
            lv.shown = None
            lv.quad.has_image = False
        planes = tuple(view.clip_planes) + tuple(layer.clip_planes)
        if lv.cells is not None:
            lv.cells.set_clip_planes(planes)
            lv.mean_depth = _box_depth(layer, view)
        lv.cell_frames = self.progressive and not self._force_exact and not self.cells_fast()
        if lv.cell_frames:
            # the trilinear stand-in until a worker drew the exact frame of this view
            done = geometry is not None and self._exact_shown(layer, lv, view)
            stand_in = not done
        else:
            # while the camera (or the isovalue) moves: the stand-in while its tets are made
            stand_in = self.progressive and self._interacting and not self._force_exact \
                and geometry is None
        mesh = layer.cell_proxy(blocking=False) if stand_in else None
        if mesh is not None:
            from splineviz.render.cell_projection import ProxySurface

            if lv.proxy is None:
                lv.proxy = ProxySurface()
                self.renderer.AddActor(lv.proxy.actor)
            if lv.proxy.mesh is not mesh:
                lv.proxy.set_mesh(mesh)
            lv.proxy.set_clip_planes(planes)
        lv.proxy_shown = mesh is not None
        self._apply_appearance(layer, lv)
        return done if lv.cell_frames else geometry is not None and not lv.proxy_shown

    def single_sample_for_cells(self) -> None:
        """Turn the window's multisampling off when a layer is drawn by cell projection
        (call before the window's first render; an off-screen picture's window). Its
        shader then casts one ray per pixel, through the pixel's centre, as the ray caster
        does: with 8 samples it cast 8 (one per sample, each tet's front face covering only
        some of a pixel's samples) for twice the frame time on software OpenGL and a
        picture antialiased where the ray caster's is not."""
        if any(layer.visible and self.renderer_of(layer) == CELL_PROJECTION
               for layer in self.layers):
            self.plotter.render_window.SetMultiSamples(0)

    def renderer_of(self, layer: IsosurfaceLayer, probe: bool = True) -> str | None:
        """What draws ``layer`` in this view: its :meth:`IsosurfaceLayer.renderer_choice`,
        except that a surface cut by more clip planes (the view's and its own) than cell
        projection takes (:data:`~splineviz.render.cell_projection.MAX_CLIP_PLANES`) is ray
        cast. None: ``"auto"`` before OpenCL was probed (``probe=False``)."""
        from splineviz.render.cell_projection import MAX_CLIP_PLANES

        choice = layer.renderer_choice(probe)
        if choice is None:
            return None
        if choice.renderer == CELL_PROJECTION and \
                len(self._clip_planes) + len(layer.clip_planes) > MAX_CLIP_PLANES:
            return RAY_CASTING
        return choice.renderer

    def shows_stand_in(self, layer: IsosurfaceLayer) -> bool:
        """Whether this view shows ``layer``'s trilinear stand-in instead of its exact
        cell-projected surface now."""
        lv = self._views[id(layer)]
        return lv.by_cells and lv.proxy_shown

    def drawn_by_cells(self, layer: IsosurfaceLayer) -> bool:
        """Whether this view draws ``layer`` by cell projection, its tets current (no
        frame of it is due)."""
        lv = self._views[id(layer)]
        return lv.by_cells and lv.cells is not None and layer.cells_current(
            lv.cells.geometry)

    def _show(self, layer: IsosurfaceLayer, rf: RenderedFrame) -> None:
        lv = self._views.get(id(layer))
        if lv is None:
            return
        f = rf.frame
        cam = rf.view.camera
        if rf.textures is None:
            _prepare(rf)
        lv.quad.set_textures(f.hit.shape[::-1], *rf.textures)
        lv.shown = rf
        self._apply_colors(layer, lv)
        w, h = rf.view.size
        t = np.tan(np.radians(cam.view_angle) / 2.0)
        lv.quad.set_view_scale(t * w / h, t)
        lv.shown = rf
        lv.mean_depth = rf.mean_depth
        self._apply_appearance(layer, lv)

    def _is_current(self, layer, lv, view) -> bool:
        return (lv.shown is not None and lv.shown.view.key() == view.key()
                and lv.shown.state == layer.state)

    def _exact_shown(self, layer, lv, view) -> bool:
        """Whether the layer's quad shows its exact frame of ``view`` and its state."""
        return self._is_current(layer, lv, view) and lv.shown.final

    def _preview_scale(self, layer, lv, view,
                       first: float = FIRST_PREVIEW_SCALE) -> tuple[float, bool]:
        """(scale, use fast caster) of a preview that fits :data:`PREVIEW_BUDGET_S`.

        The scale follows the time of the last preview (frames have fixed costs, so a
        per-pixel estimate would overshoot): it grows or shrinks by the square root of the
        budget ratio, at most by a factor two per frame; the time of a preview of a size not
        cast before is not counted (it includes the kernel's compilation). The frame is cast
        at the largest of :data:`PREVIEW_LEVELS` not above that scale, so a level is left
        upwards only when a preview took at most half the budget. A layer's first preview
        is cast at ``first``.
        """
        if lv.shown is None or lv.preview_scale is None:
            lv.preview_scale = first
        elif lv.preview_seconds:
            # the last *preview*: an exact frame shown since does not count, but a preview
            # at scale 1 does (else the scale would stay at 1 however slow those frames are)
            ratio = float(np.sqrt(PREVIEW_BUDGET_S / lv.preview_seconds))
            lv.preview_scale *= float(np.clip(ratio, 0.5, 2.0))
        lv.preview_scale = float(np.clip(lv.preview_scale, MIN_PREVIEW_SCALE,
                                         max(self.max_preview_scale, MIN_PREVIEW_SCALE)))
        level = max((v for v in PREVIEW_LEVELS if v <= lv.preview_scale * (1 + 1e-9)),
                    default=MIN_PREVIEW_SCALE)
        return max(level, MIN_PREVIEW_SCALE), True

    def _before_render(self, *_args) -> None:
        t0 = time.perf_counter()
        self._reset_clipping_range()
        view = self.view_state()
        # read by refine() in a worker: a bricked frame of an older view is given up
        self._latest_key = view.key()
        stale = []
        blocking = not self.progressive or self._force_exact
        for layer in self.layers:
            lv = self._views[id(layer)]
            if not layer.visible:
                lv.quad.actor.VisibilityOff()
                if lv.cells is not None:
                    lv.cells.set_visible(False)
                if lv.proxy is not None:
                    lv.proxy.actor.VisibilityOff()
                continue
            renderer = self.renderer_of(layer, probe=blocking)
            if renderer is None:  # "auto" before anyone probed OpenCL: the worker does
                stale.append(layer)
                continue
            if renderer == CELL_PROJECTION:
                if not self._draw_cells(layer, lv, view, blocking):
                    stale.append(layer)
                continue
            if lv.by_cells:
                self._drop_cells(lv)
                lv.by_cells = lv.cell_frames = False
                # a cell-projected frame in the quad is not the ray caster's
                lv.shown = None
                lv.quad.has_image = False
            if self._is_current(layer, lv, view):
                if self.progressive and not lv.shown.final:
                    # a preview of this very view (the last drag step's, or a wheel step's
                    # cast while interacting): no new preview, but the exact frame is due
                    stale.append(layer)
                continue
            if not self.progressive or self._force_exact:
                self._show(layer, layer.compute(view))
            elif (self._resized and lv.shown is not None and lv.shown.state == layer.state
                  and tuple(lv.shown.view.size) != tuple(view.size)):
                stale.append(layer)
            else:
                scale, fast = self._preview_scale(layer, lv, view)
                t_preview = time.perf_counter()
                rf = layer.compute(view, scale=scale, preview=fast, blocking=False)
                if rf is None:  # a worker holds the caster: keep the old frame, and the scale
                    lv.preview_seconds = None
                else:
                    size = rf.frame.hit.shape
                    lv.preview_scale = rf.scale  # the next step starts from the level cast
                    self._show(layer, rf)
                    # the whole preview counts against the budget, not only the cast:
                    # reading its positions and normals, the colour-by values and making and
                    # uploading its textures here took as long again at the larger levels
                    # (two previews per drag step in a split view: 120-180 ms steps)
                    spent = time.perf_counter() - t_preview
                    lv.preview_seconds = spent if size in lv.preview_sizes else None
                    lv.preview_sizes.add(size)
                stale.append(layer)
        for layer in self.volume_layers:
            if self._volume_preview(layer, view):
                stale.append(layer)
        self._resized = False
        self._cells_drawn = any(
            layer.visible and lv.by_cells and lv.cells is not None and not lv.cell_frames
            and not lv.proxy_shown
            for layer, lv in ((la, self._views[id(la)]) for la in self.layers))
        self._order_quads()
        self._fit_scalar_bars()
        self.last_frame_s = time.perf_counter() - t0
        self.frame_times.append(self.last_frame_s)
        del self.frame_times[:-50]
        if stale and self.request_refine is not None and not self._interacting:
            self.request_refine()

    def _volume_current(self, layer: VolumeLayer, view: ViewState, final: bool) -> bool:
        """Whether the volume layer shows a frame of ``view``, its state and the depth of
        the last render (and, with ``final``, an exact one)."""
        vf = self._vviews[id(layer)].shown
        return (vf is not None and vf.view.key() == view.key() and vf.state == layer.state
                and self._depth is not None and vf.depth_sig == self._depth[2]
                and (vf.final or not final))

    def _volume_preview(self, layer: VolumeLayer, view: ViewState) -> bool:
        """Before a render: hide, keep or preview the volume layer; True when its exact
        frame is due. The preview's rays end at the last render's depth (the same view
        unless the camera moves; then it is a frame behind), and it is cast only at a size
        cast before (a new size compiles the kernel: the refine worker casts it first)."""
        vv = self._vviews[id(layer)]
        if not layer.visible:
            vv.actor.VisibilityOff()
            return False
        if self._volume_current(layer, view, final=True):
            return False
        if not self.progressive or self._force_exact:
            return False  # cast after the scene is drawn (_after_render)
        shown = vv.shown
        current = shown is not None and self._volume_current(layer, view, final=False)
        if not current and self._depth is not None \
                and tuple(self._depth[1].shape) == (view.size[1], view.size[0]):
            scale, _ = self._preview_scale(layer, vv, view, FIRST_VOLUME_PREVIEW_SCALE)
            if layer.is_warm(view, scale):
                t0 = time.perf_counter()
                vf = layer.compute(view, self._depth[1], self._depth[2], scale=scale,
                                   preview=True, blocking=False)
                if vf is not None:
                    vv.preview_scale = scale
                    self._show_volume(layer, vf)
                    vv.preview_seconds = time.perf_counter() - t0
            else:
                vv.preview_seconds = None
        return True

    def _show_volume(self, layer: VolumeLayer, vf: VolumeFrame) -> None:
        """Put the frame's image in the layer's overlay, at the window size of its view."""
        from vtkmodules.util.numpy_support import numpy_to_vtk

        vv = self._vviews.get(id(layer))
        if vv is None:
            return
        img = vf.image
        w, h = vf.view.size
        if img.shape[:2] != (h, w):
            rows = np.minimum((np.arange(h) + 0.5) * img.shape[0] / h, img.shape[0] - 1)
            cols = np.minimum((np.arange(w) + 0.5) * img.shape[1] / w, img.shape[1] - 1)
            img = img[rows.astype(int)[:, None], cols.astype(int)[None, :]]
        arr = numpy_to_vtk(np.ascontiguousarray(img).reshape(-1, 4), deep=True)
        arr.SetNumberOfComponents(4)
        vv.image.SetDimensions(w, h, 1)
        vv.image.GetPointData().SetScalars(arr)
        vv.image.Modified()
        vv.shown = vf
        vv.actor.SetVisibility(bool(layer.visible))

    def _after_render(self, *_args) -> None:
        """After the scene's pass (before the overlay's): read the window depth the volume
        layers end their rays at; cast their exact frames now (synchronous mode) or ask for
        them when the depth changed under an exact frame (a new mesh, an exact isosurface)."""
        visible = [layer for layer in self.volume_layers if layer.visible]
        if not visible:
            self._depth = None
            return
        from splineviz.render.volume_rendering import window_depth

        w, h = self.window_size()
        depth = window_depth(self.plotter, w, h)
        view = self.view_state()
        self._depth = (view.key(), depth, depth_signature(depth))
        due = [layer for layer in visible if not self._volume_current(layer, view, True)]
        if not due:
            return
        if not self.progressive or self._force_exact:
            for layer in due:
                self._show_volume(layer, layer.compute(view, depth, self._depth[2]))
        elif self.request_refine is not None and not self._interacting:
            self.request_refine()

    def _fit_scalar_bars(self) -> None:
        """Fewer, wider-spread labels on the scalar bars of a narrow window (one of two
        side-by-side views): five labels of ~7 characters overlap below ~480 pixels. Each
        bar is :data:`BAR_HEIGHT_PX` high whatever the window's height: a bar of a fixed
        share of a low window had no room for its title above its labels (they overlapped)."""
        w, h = self.window_size()
        narrow = w < NARROW_BAR_PX
        height = min(BAR_HEIGHT_PX / h, 0.3)
        for index, layer in enumerate(self.layers):
            bar = self._views[id(layer)].scalar_bar
            bar.SetNumberOfLabels(3 if narrow else 5)
            bar.SetWidth(0.8 if narrow else 0.5)
            bar.SetHeight(height)
            bar.SetPosition(0.1 if narrow else 0.25, 0.02 + (height + 0.01) * index)

    def _reset_clipping_range(self) -> None:
        """Near/far planes around the visible props *and* every visible layer's data box:
        a layer whose quad has no image yet must count too, or its first exact frame
        would be made for another clipping range than the frames after it."""
        bounds = np.array(self.renderer.ComputeVisiblePropBounds(), dtype=float)
        boxes = [np.ravel(world_bounds(layer.volume)) for layer in self.layers
                 if layer.visible]
        if bounds[0] <= bounds[1]:
            boxes.append(bounds)
        if not boxes:
            self.renderer.ResetCameraClippingRange()
            return
        b = np.stack(boxes)
        self.renderer.ResetCameraClippingRange(b[:, 0].min(), b[:, 1].max(), b[:, 2].min(),
                                               b[:, 3].max(), b[:, 4].min(), b[:, 5].max())

    def _order_quads(self) -> None:
        """Quads (and cell-projection actors) after all other props: opaque, then
        translucent from far to near."""
        quads = []
        for layer in self.layers:
            lv = self._views[id(layer)]
            actors = lv.cells.actors if lv.by_cells and lv.cells is not None \
                and not lv.cell_frames else (lv.quad.actor,)
            quads.append((layer.opacity < 1.0, -lv.mean_depth, actors))
        for _, _, actors in quads:
            for actor in actors:
                self.renderer.RemoveActor(actor)
        for _, _, actors in sorted(quads, key=lambda q: (q[0], q[1])):
            for actor in actors:
                self.renderer.AddActor(actor)

    def needs_refine(self) -> bool:
        """Whether a visible layer shows a preview or a frame of another view (or waits
        for its cell-projection tets, or for the OpenCL probe of its "auto" renderer)."""
        view = self.view_state()
        for layer in self.layers:
            lv = self._views[id(layer)]
            if not layer.visible:
                continue
            renderer = self.renderer_of(layer, probe=False)
            if renderer == CELL_PROJECTION:
                if not layer.cells_current() or (
                        lv.cell_frames and not self._exact_shown(layer, lv, view)):
                    return True
            elif renderer is None or not self._exact_shown(layer, lv, view):
                return True
        return any(layer.visible and not self._volume_current(layer, view, final=True)
                   for layer in self.volume_layers)

    def refine(self, view: ViewState | None = None, cancelled=None, job=None, partial=None):
        """Exact frames of all visible layers that show a preview (thread safe).

        Parameters
        ----------
        view : ViewState or None
            The view to render for (taken now when None; the caller takes it in the main
            thread before starting a worker).
        cancelled : callable or None
            Returns True to stop between layers (and between the steps of a layer).
        job : object with ``progress(fraction, message)`` and ``cancelled``, optional
            Told the bricks done of a chunked volume's frame (the GUI's job runner passes
            its job) and the steps done of a frame cast coarse to fine; such a frame is also
            given up once the view moved on (bricks still out are cancelled) and refined
            again for the new view.
        partial : callable, optional
            ``partial(layer, RenderedFrame)``, called in this thread with the frames made on
            the way: a preview first when the shown frame is of another state of the layer
            (its model or data changed), then each coarser step of
            :meth:`IsosurfaceLayer.exact_scales` (for such a slow model the preview is of
            full resolution). None: exact frames only.

        Returns
        -------
        list of (layer, RenderedFrame)
        """
        view = self.view_state() if view is None else view

        def given_up():
            return ((cancelled is not None and cancelled())
                    or bool(getattr(job, "cancelled", False))
                    or self._latest_key not in (None, view.key()))

        out = []
        for layer in list(self.layers):
            if given_up():
                break
            lv = self._views.get(id(layer))
            if lv is None or not layer.visible:
                continue
            if self.renderer_of(layer) == CELL_PROJECTION:  # probes OpenCL for "auto"
                if not layer.cells_current():
                    out.append((layer, layer.cell_geometry()))
                if self.progressive and not self.cells_fast() \
                        and not self._exact_shown(layer, lv, view):
                    layer.cell_proxy()  # a large volume's stand-in is made here
                    if given_up():
                        break
                    out.append((layer, layer.cell_frame(view)))
                continue
            if self._exact_shown(layer, lv, view):
                continue
            shown = lv.shown
            scales = layer.exact_scales() if partial is not None else (1.0,)
            # a slow model or bricks: a sharp preview from the cheaper caster (a chunked
            # volume's coarse level) while it is cast (after one of a preview size: the GUI
            # thread previews from it while the camera moves)
            sharp = len(scales) > 1 or layer.coarse_preview
            if partial is not None and (shown is None or shown.state != layer.state
                                        or (sharp and shown.scale < 1.0)):
                for size in (PREVIEW_LEVELS[4], 1.0) if sharp else (PREVIEW_LEVELS[4],):
                    rf = layer.compute(view, scale=size, preview=True)
                    if rf is None or given_up():
                        break
                    _prepare(rf)
                    partial(layer, rf)
            total = sum(s * s for s in scales)
            rf = None
            for i, scale in enumerate(scales):
                if job is not None and len(scales) > 1:
                    job.progress(sum(s * s for s in scales[:i]) / total,
                                 f"{layer.name}: {scale:.3g} of full resolution")
                if i and given_up():
                    rf = None
                    break
                rf = layer.compute(view, scale=scale, progress=_brick_progress(job, layer),
                                   cancelled=given_up)
                if rf is None:
                    break
                _prepare(rf)  # the textures, here in the worker, not in the GUI thread
                if not rf.final:
                    partial(layer, rf)
            if rf is not None and rf.final:
                out.append((layer, rf))
        depth = self._depth
        for layer in list(self.volume_layers):
            if given_up() or depth is None or depth[0] != view.key():
                break
            vv = self._vviews.get(id(layer))
            if vv is None or not layer.visible or self._volume_current(layer, view, True):
                continue
            if partial is not None and (vv.shown is None or vv.shown.state != layer.state
                                        or vv.shown.view.key() != view.key()):
                vf = layer.compute(view, depth[1], depth[2], scale=PREVIEW_LEVELS[4],
                                   preview=True)
                if given_up():
                    break
                partial(layer, vf)
            out.append((layer, layer.compute(view, depth[1], depth[2])))
        return out

    def apply(self, results) -> bool:
        """Show refined frames that still match the view and the layers; True if any did."""
        view = self.view_state()
        used = False
        for layer, rf in results:
            if isinstance(layer, VolumeLayer):
                if layer in self.volume_layers and rf.view.key() == view.key() \
                        and rf.state == layer.state:
                    self._show_volume(layer, rf)
                    used = True
                continue
            if layer not in self.layers:
                continue
            if not isinstance(rf, RenderedFrame):
                # a cell geometry (refine): the next render draws it while it is current
                used = used or layer.cells_current(rf)
            elif rf.view.key() == view.key() and rf.state == layer.state:
                if rf.path == CELL_PROJECTION:
                    self.cells_seconds = rf.seconds
                self._show(layer, rf)
                used = True
        return used

    def render_exact(self) -> None:
        """One synchronous render with exact frames (for screenshots)."""
        self._force_exact = True
        try:
            # the window itself: pyvista's render() does nothing before show()
            self.plotter.render_window.Render()
        finally:
            self._force_exact = False

    def close(self) -> None:
        self.renderer.RemoveObserver(self._observer)
        self.renderer.RemoveObserver(self._end_observer)
        for tag in self._window_observers:
            self.plotter.render_window.RemoveObserver(tag)
        for layer in list(self.layers):
            self.remove_layer(layer)
        for layer in list(self.volume_layers):
            self.remove_volume_layer(layer)
        if self._overlay is not None:
            self.plotter.render_window.RemoveRenderer(self._overlay)
            self._overlay = None
        if self.range_link is not None:
            self.range_link.forget(self)


def _brick_progress(job, layer):
    """``progress(done, total)`` of a chunked layer's bricks for a job, or None."""
    if job is None:
        return None

    def progress(done, total):
        job.progress(done / max(total, 1), f"{layer.name}: bricks {done}/{total}")

    return progress


def _scalar_bar(index: int):
    """A hidden horizontal scalar bar for the ``index``-th layer (stacked from the bottom)."""
    import vtk

    bar = vtk.vtkScalarBarActor()
    bar.SetOrientationToHorizontal()
    bar.SetLookupTable(vtk.vtkLookupTable())
    bar.SetNumberOfLabels(5)
    bar.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    bar.SetPosition(0.25, 0.02 + 0.11 * index)
    bar.SetWidth(0.5)
    bar.SetHeight(0.1)
    # VTK fits the title and labels into the box (unconstrained sizes overlapped there);
    # the box is a fixed number of pixels high (:meth:`SplineScene._fit_scalar_bars`), so
    # the text has one size in every window
    bar.SetBarRatio(0.3)
    bar.UnconstrainedFontSizeOff()
    for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        prop.SetFontSize(12)
        prop.ShadowOff()
        prop.BoldOff()
        prop.ItalicOff()
    bar.VisibilityOff()
    return bar


def _update_scalar_bar(bar, cmap: str, lo: float, hi: float, title: str) -> None:
    table = lut(cmap)
    lt = bar.GetLookupTable()
    lt.SetNumberOfTableValues(len(table))
    for i, (r, g, b) in enumerate(table):
        lt.SetTableValue(i, r / 255.0, g / 255.0, b / 255.0, 1.0)
    lt.SetRange(lo, hi)
    lt.Build()
    bar.SetTitle(title)
    bar.Modified()


def _box_depth(layer: IsosurfaceLayer, view: ViewState) -> float:
    """Window depth of the centre of the layer's data box (orders a translucent surface
    drawn by cell projection among the others, as a frame's mean hit depth does)."""
    centre = np.asarray(world_bounds(layer.volume), dtype=np.float64).mean(axis=1)
    cam = view.camera
    return float(np.clip(cam.window_depth(centre[None], cam.clipping_range)[0], 0.0, 1.0))


def _prepare(rf: RenderedFrame) -> None:
    """Fill a frame's upload-ready textures and mean depth (thread safe: NumPy only)."""
    f = rf.frame
    rf.textures = frame_textures(f.hit, f.normal, f.depth, rf.view.camera.basis())
    rf.mean_depth = float(f.depth[f.hit].mean()) if f.hit.any() else 1.0


def offscreen_screenshot(scene: SplineScene, filename=None, size=None,
                         transparent_background: bool = False, background=None) -> np.ndarray:
    """Render ``scene`` again in an off-screen window of ``size`` and return the image.

    The new window gets the same camera (view angle kept, so a different aspect ratio shows
    more or less at the sides), the same layers (exact frames) and the same props.

    Parameters
    ----------
    scene : SplineScene
    filename : str or Path or None
        PNG to write.
    size : (width, height) or None (the scene's window size)
    transparent_background : bool
        RGBA image with alpha 0 where nothing was drawn.

    Returns
    -------
    (H, W, 3) or (H, W, 4) uint8
    """
    import pyvista as pv

    w, h = scene.window_size() if size is None else (int(size[0]), int(size[1]))
    if w < 1 or h < 1 or w > 16384 or h > 16384:
        raise SceneError(f"screenshot size must be 1..16384 pixels per side, got {w}x{h}")
    pl = pv.Plotter(off_screen=True, window_size=(w, h))
    try:
        bg = background if background is not None else scene.renderer.GetBackground()
        pl.set_background(bg)
        copy = SplineScene(pl, progressive=False)
        # the picture in the colours of the view: its frame of another size would have
        # other percentiles (and the view's may be shared with a split's other half)
        copy.range_link = FixedRanges({range_key(layer): scene.color_range(layer)
                                       for layer in scene.layers
                                       if scene.color_range(layer) is not None})
        for rec in scene.props.values():
            if rec.visible:
                copy.add_mesh(rec.name, rec.dataset, kind=rec.kind, **rec.options)
        for layer in scene.layers:
            copy.add_layer(layer)
        for layer in scene.volume_layers:
            copy.add_volume_layer(layer)
        copy.set_clip_planes(scene.clip_planes)
        copy.single_sample_for_cells()
        pl.renderer.GetActiveCamera().DeepCopy(scene.renderer.GetActiveCamera())
        pl.camera_set = True  # else pyvista resets the camera on the first render
        copy.render_exact()
        img = pl.screenshot(filename, transparent_background=transparent_background,
                            return_img=True)
        copy.close()
        return img
    finally:
        pl.close()
