"""An isosurface layer: the state of one ray-cast spline isosurface, free of any view.

A layer reads the properties of its isosurface node (spline model, isovalue, colour,
opacity, material, colour by) and holds the volume's data and the ray casters that make its
frames. Views (:class:`~splineviz.render.scene.
SplineScene`) ask it for frames of *their* camera and size with :meth:`IsosurfaceLayer.compute`
and show them with a :class:`~splineviz.render.quad.FrameQuad`; several views (the window,
an off-screen export) can show one layer. ``compute`` may run in a worker thread: each ray
caster has its own lock, so a new model's caster never waits for a worker still casting
with the old one.

Preview: models without an OpenCL kernel (plugins) render through the NumPy reference
(seconds to minutes per frame). While the camera moves, and after a change of model, a
layer renders a *preview* at reduced resolution with a cheaper caster (:attr:`RenderedFrame.
model` says which): the trilinear OpenCL kernel, or the previous model's kernel caster right
after a model switch (same data, same isovalue; the surfaces differ by the model error
only). The exact frame follows in a worker (thesis §6.3: interactive rates for the
trilinear model, exact pictures for the smooth ones); a model without a kernel is cast
coarse to fine there (:meth:`IsosurfaceLayer.exact_scales`), each step shown. A chunked
volume's previews ray cast its coarse level (an OME-Zarr pyramid level or a strided
downsample, in memory: :meth:`~splineviz.core.chunked.ChunkedVolume.preview_volume`) with
the trilinear kernel, at any size in milliseconds (:attr:`IsosurfaceLayer.coarse_preview`),
while the exact frame is made in bricks on dask workers.

Renderer (thesis ch. 6): :meth:`IsosurfaceLayer.renderer_choice` says whether the node's
surface is ray cast or drawn by cell projection (:mod:`splineviz.core.renderers`); for cell
projection the layer makes the relevant tets (:meth:`IsosurfaceLayer.cell_geometry`, once per
volume, model and isovalue) and the views draw them with their own
:class:`~splineviz.render.cell_projection.CellProjectionLayer` actors instead of frames.

The GUI thread calls :meth:`compute` with ``blocking=False``: it takes no lock it would
have to wait for, builds no caster and evaluates no spline of a model without a kernel
(a plugin's evaluation may take any time); without a free caster it returns None and the
view keeps its last frame.
"""

from __future__ import annotations

import contextlib
import threading
import time
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from splineviz.compute.device import opencl_known, opencl_works
from splineviz.core.camera import Camera
from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.core.frame import from_world
from splineviz.core.material import MATERIALS, Material
from splineviz.core.raycast_reference import Frame
from splineviz.core.renderers import AUTO, CELL_PROJECTION, RendererChoice, choose_renderer
from splineviz.core.volume import Volume
from splineviz.model import nodes

if TYPE_CHECKING:
    from splineviz.render.cell_projection import CellGeometry

#: default front colours of successive layers (a qualitative palette: tell surfaces apart)
PALETTE = nodes.PALETTE


class LayerError(SplinevizError, ValueError):
    """Bad isosurface layer settings (unknown model, isovalue or opacity out of range)."""


@dataclass(frozen=True)
class ViewState:
    """What a frame depends on in the view: camera (with clipping range) and pixel size."""

    camera: Camera
    size: tuple[int, int]
    clip_planes: tuple = ()

    def key(self) -> tuple:
        c = self.camera
        planes = tuple(tuple(np.round(np.ravel(p), 12)) for p in self.clip_planes)
        return (c.position, c.focal_point, c.view_up, c.view_angle, c.clipping_range,
                tuple(self.size), planes)


@dataclass
class RenderedFrame:
    """A frame with what it was made for (the key of the view and the layer's state)."""

    frame: Frame
    view: ViewState
    state: tuple
    scale: float
    seconds: float
    path: str
    stats: dict = field(default_factory=dict)
    #: upload-ready textures and the mean hit depth (filled by the scene, in the thread that
    #: made the frame when it can)
    textures: tuple | None = None
    mean_depth: float = 1.0
    #: (H, W) colour-by scalars at the hits (NaN elsewhere), None when not coloured by one
    scalars: np.ndarray | None = None
    #: the spline model that cast the frame (a preview's may be a cheaper one)
    model: str = ""
    #: the data a preview was cast from when not the layer's own samples: a chunked
    #: volume's coarse level (:attr:`splineviz.core.chunked.Level.label`), else ""
    source: str = ""

    @property
    def final(self) -> bool:
        return self.scale >= 1.0 and self.path != "preview"


def make_caster(volume, model: str, device=None, options=None):
    """The ray caster of a layer: a :class:`~splineviz.compute.raycast.RayCaster` of an
    in-memory volume, a :class:`~splineviz.compute.bricked.BrickedRayCaster` (bricks on dask
    workers) of a :class:`~splineviz.core.chunked.ChunkedVolume`."""
    from splineviz.core.chunked import ChunkedVolume

    if isinstance(volume, ChunkedVolume):
        from splineviz.compute.bricked import BrickedRayCaster

        return BrickedRayCaster(volume, model=model, device=device, **dict(options or {}))
    from splineviz.compute.raycast import RayCaster

    return RayCaster(volume, model=model, device=device, **dict(options or {}))


#: resolution factors of the exact frame of a model without an OpenCL kernel, cast one after
#: the other in the worker: each step is shown (a coarser image of the exact surface) and
#: is a point where the frame can be given up; the steps before the last add a third
COARSE_TO_FINE = (0.125, 0.25, 0.5, 1.0)


@dataclass(eq=False)
class _Caster:
    """A ray caster and the lock of its use (one lock per caster, see module docstring)."""

    rc: object
    lock: threading.Lock = field(default_factory=threading.Lock)
    #: ((view width, height), scale) of the frames cast so far: PoCL compiles the kernel
    #: anew for each new frame size (0.2-0.7 s), which the GUI thread leaves to workers
    #: for a fallback caster
    sizes: set = field(default_factory=set)
    #: the data it casts when not the layer's own (:attr:`RenderedFrame.source`)
    source: str = ""

    def scale_cast(self, size, scale: float) -> float | None:
        """The largest resolution factor not above ``scale`` this caster has cast a frame
        of view ``size`` at, or None."""
        return max((s for v, s in self.sizes if v == tuple(size) and s <= scale), default=None)

    @property
    def path(self) -> str:
        return self.rc.stats.get("path", "numpy")


class _DeviceUse:
    """How many worker threads cast on the OpenCL device now (thread safe). The GUI thread
    casts no preview meanwhile: its kernel would queue behind theirs on the device (a
    worker's full frame took the GUI thread's 20 ms preview to 80-140 ms on PoCL)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._count = 0

    def __enter__(self):
        with self._lock:
            self._count += 1

    def __exit__(self, *exc):
        with self._lock:
            self._count -= 1

    @property
    def busy(self) -> bool:
        return self._count > 0


_WORKERS_ON_DEVICE = _DeviceUse()


#: volumes of at most this many samples get the stand-in mesh of a cell-projected surface
#: made in the GUI thread while the camera or the isovalue moves (flying edges took 1-2 ms
#: for 41^3 samples)
INLINE_PROXY_SAMPLES = 1_000_000

#: node properties whose change needs new frames (any other changes only the shading
#: uniforms or the colouring of shown frames)
FRAME_PROPERTIES = frozenset({"model", "k", "isovalue", "color_by", "renderer"})


class IsosurfaceLayer:
    """One spline isosurface of a volume (see module docstring).

    The layer reads its :class:`~splineviz.model.IsosurfaceNode` (``node``) and holds no
    copy of its properties: a change of the node tells the layer's listeners (``"frame"``
    for :data:`FRAME_PROPERTIES`, else ``"appearance"``). What the node names by id (its
    volume's data, a colour-by volume or reference surface) is given by the owner
    (:meth:`set_volume`, :meth:`set_color_by`); ``visible`` is this view's: the node's
    and its volume's visibility and the view's side. Without ``node`` the layer makes
    its own from the keyword arguments (scripts, tests); the ``set_*`` methods write to
    the node either way.

    Parameters
    ----------
    volume : Volume
    model : str
        A key of the model registry :data:`splineviz.core.splines.MODELS`.
    isovalue : float or None
        ``None``: the middle of the data range.
    color : (3,) float in [0, 1]
    opacity : float in (0, 1]
    name : str
    device : str or None
        OpenCL device preference passed to :class:`splineviz.RayCaster`.
    material : str
        A key of :data:`splineviz.core.material.MATERIALS`.
    model_options : dict, optional
        Keyword arguments of the model (``k``).
    node : IsosurfaceNode, optional
        The node to show; the other settings are then read from it.
    """

    def __init__(self, volume: Volume, model: str = "trilinear", isovalue=None,
                 color=PALETTE[0], opacity: float = 1.0, name: str = "isosurface",
                 device: str | None = None, material: str = "default", model_options=None,
                 node: nodes.IsosurfaceNode | None = None):
        if node is None:
            iso = (0.5 * sum(volume.finite_range) if isovalue is None else isovalue)
            node = _layer_call(lambda: nodes.IsosurfaceNode(
                name=name, model=model, isovalue=iso, color=color, opacity=opacity,
                material=material, **dict(model_options or {})))
        self.node = node
        self.visible = True
        self._device = device
        #: makes casters (in workers only); the casters' own locks guard their use
        self._build_lock = threading.Lock()
        #: guards the cache of colour-by splines (``_splines``)
        self._spline_lock = threading.Lock()
        self._listeners = []
        self._volume = volume
        #: (model, options) the casters and splines are made for
        self._cast = (node.model, node.model_options())
        #: clip planes of this layer alone, added to the view's (see :meth:`set_clip_planes`)
        self.clip_planes: tuple = ()
        self._version = 0
        #: the caster of the node's model, and a cheaper kernel caster for previews
        self._exact: _Caster | None = None
        self._fast: _Caster | None = None
        #: counts the droppings of casters: a caster built meanwhile is not kept
        self._generation = 0
        self.last_stats: dict = {}
        self._limits = (0.0, 1.0)
        self._keep_limits()
        self._color_volume: Volume | None = None
        self._color_reference: tuple | None = None  # (volume, model, options, isovalue)
        self._splines: dict = {}  # "own" / "other" -> Spline for the colour-by values
        #: cell projection: ((volume id, model, options), spline) and (key, CellGeometry)
        #: of the last geometry made, under their lock (made in a worker in the GUI)
        self._cell_lock = threading.Lock()
        self._cell_spline: tuple | None = None
        self._cells: tuple | None = None
        #: ((volume id, isovalue), vtkPolyData) of the last stand-in mesh made
        self._cell_proxy: tuple | None = None
        node.events.connect(self._node_changed)

    def close(self) -> None:
        """Stop following the node."""
        self.node.events.disconnect(self._node_changed)

    # -- events --------------------------------------------------------------------------

    def connect(self, callback) -> None:
        """Call ``callback(layer, what)`` after a change; ``what`` is ``"frame"`` when frames
        must be recomputed and ``"appearance"`` when only the shading uniforms changed."""
        self._listeners.append(callback)

    def disconnect(self, callback) -> None:
        if callback in self._listeners:
            self._listeners.remove(callback)

    def _emit(self, what: str) -> None:
        if what == "frame":
            self._version += 1
        for cb in list(self._listeners):
            cb(self, what)

    def _node_changed(self, info) -> None:
        name = info.signal.name
        if name in ("model", "k"):
            cast = (self.node.model, self.node.model_options())
            if cast == self._cast:
                return
            # drop the caster without waiting for a worker that uses it (see set_volume);
            # a kernel caster of the old model previews the new one until its own exists
            self._cast = cast
            old = self._exact
            if self._fast is None and old is not None and old.path == "opencl":
                self._fast = old
            self._drop(keep_fast=True)
        elif name in ("color_min", "color_max"):
            self._keep_limits()
        self._emit("frame" if name in FRAME_PROPERTIES else "appearance")

    def _keep_limits(self) -> None:
        # a panel moves one end of the manual range past the other for a moment: the map
        # keeps the last valid range meanwhile
        lo, hi = self.node.color_min, self.node.color_max
        if lo < hi:
            self._limits = (lo, hi)

    # -- state (read from the node) ------------------------------------------------------

    @property
    def name(self) -> str:
        return self.node.name

    @property
    def volume(self) -> Volume:
        return self._volume

    @property
    def model(self) -> str:
        return self.node.model

    @property
    def isovalue(self) -> float:
        return self.node.isovalue

    @property
    def color(self) -> tuple:
        return tuple(self.node.color)

    @property
    def opacity(self) -> float:
        return self.node.opacity

    @property
    def material_name(self) -> str:
        return self.node.material

    @property
    def material(self) -> Material:
        return MATERIALS[self.node.material]

    @property
    def color_by(self) -> str:
        return self.node.color_by

    @property
    def color_map(self) -> str:
        return self.node.color_map

    @property
    def color_range(self) -> str:
        return self.node.color_range

    @property
    def color_limits(self) -> tuple[float, float]:
        """The manual ``(lo, hi)`` of the colour map (the last valid one)."""
        return self._limits

    @property
    def state(self) -> tuple:
        """Changes whenever frames of this layer must be recomputed."""
        return (self._version, self.node.model, self.node.isovalue)

    # -- renderer (thesis ch. 6: ray casting or cell projection) ------------------------

    def renderer_choice(self, probe: bool = True) -> RendererChoice | None:
        """What draws this surface now (:func:`splineviz.core.renderers.choose_renderer`
        of the node's ``renderer``, model and colour by, and whether OpenCL works here).

        ``"auto"`` needs to know whether an OpenCL device works: ``probe=False`` (the GUI
        thread: opening a device takes a context and a kernel build) returns None while
        nobody has asked yet."""
        node = self.node
        opencl = True
        if node.renderer == AUTO or self._device == "numpy":
            opencl = opencl_works(self._device) if probe else opencl_known(self._device)
            if opencl is None:
                return None
        return choose_renderer(node.renderer, node.model, node.color_by, opencl,
                               not_projectable(self._volume))

    @property
    def renderer(self) -> str:
        """``"ray-casting"`` or ``"cell-projection"`` (:meth:`renderer_choice`)."""
        return self.renderer_choice().renderer

    def _cell_key(self) -> tuple:
        return (id(self._volume), self.node.model, self.node.isovalue)

    def cells_current(self, geometry: CellGeometry | None = None) -> bool:
        """Whether the last cell geometry made (or ``geometry``) is of the layer as it is."""
        cells = self._cells
        return cells is not None and cells[0] == self._cell_key() and (
            geometry is None or geometry is cells[1])

    def cell_proxy(self, blocking: bool = True):
        """The :func:`~splineviz.render.cell_projection.trilinear_mesh` of the current
        isovalue (a vtkPolyData), made once per volume and isovalue (thread safe);
        ``blocking=False`` makes it only for a volume of at most
        :data:`INLINE_PROXY_SAMPLES` samples (milliseconds), else returns the last one if
        it is current, or None."""
        from splineviz.render.cell_projection import trilinear_mesh

        key = (id(self._volume), self.node.isovalue)
        proxy = self._cell_proxy
        if proxy is not None and proxy[0] == key:
            return proxy[1]
        if not blocking and self._volume.data.size > INLINE_PROXY_SAMPLES:
            return None
        mesh = trilinear_mesh(self._volume, key[1])
        self._cell_proxy = (key, mesh)
        return mesh

    def cell_geometry(self, blocking: bool = True) -> CellGeometry | None:
        """The relevant tets of the surface laid out for cell projection
        (:func:`splineviz.render.cell_projection.cell_geometry`), made once per volume,
        model and isovalue (thread safe). ``blocking=False`` (the GUI thread) makes
        nothing: the last one if it is current, else None."""
        from splineviz.plugins import build_spline
        from splineviz.render.cell_projection import cell_geometry

        key = self._cell_key()
        cells = self._cells
        if cells is not None and cells[0] == key:
            return cells[1]
        if not blocking:
            return None
        with self._cell_lock:
            cells = self._cells
            if cells is not None and cells[0] == key:
                return cells[1]
            spline_key = key[:2] + (tuple(sorted(self.node.model_options().items())),)
            if self._cell_spline is None or self._cell_spline[0] != spline_key:
                spline = build_spline(self._volume, self.node.model,
                                      **self.node.model_options())
                self._cell_spline = (spline_key, spline)
            t = time.perf_counter()
            geometry = cell_geometry(self._cell_spline[1], key[2])
            self._cells = (key, geometry)
            # what the status bar lists of a layer: its tets, and what draws them
            self.last_stats = {"active_tets": len(geometry.tets), "active_cells": None,
                               "classify_s": time.perf_counter() - t, "render_s": None,
                               "device": "OpenGL cell projection", "path": CELL_PROJECTION,
                               "classified": "all"}
            return geometry

    def cell_frame(self, view: ViewState) -> RenderedFrame:
        """The exact frame of the surface for ``view`` drawn by cell projection off the
        calling thread (:func:`splineviz.render.cell_frames.cell_frame`; thread safe, blocks
        until drawn), its textures made."""
        from splineviz.render.cell_frames import cell_frame
        from splineviz.render.quad import packed_textures

        state = self.state
        geometry = self.cell_geometry()
        t = time.perf_counter()
        frame, normals = cell_frame(geometry, view.camera, view.size,
                                    tuple(view.clip_planes) + self.clip_planes)
        rf = RenderedFrame(frame, view, state, 1.0, time.perf_counter() - t, CELL_PROJECTION,
                           dict(self.last_stats), model=self.model)
        rf.textures = packed_textures(normals, frame.depth)
        rf.mean_depth = float(frame.depth[frame.hit].mean()) if frame.hit.any() else 1.0
        return rf

    def set_volume(self, volume: Volume) -> None:
        """New data (e.g. smoothed); keeps model and isovalue.

        The casters are dropped, not updated: uploading the data and classifying belong in
        the thread that makes the next exact frame, and a frame a worker is still making
        from the old casters is discarded when it arrives (:meth:`compute` checks). Nothing
        here waits for a lock, so the GUI thread never waits for a ray cast.
        """
        self._volume = volume
        self._drop()
        self._emit("frame")

    def _drop(self, keep_fast: bool = False) -> None:
        """Forget the casters (and colour-by splines) without waiting for their users."""
        self._generation += 1
        self._exact = None
        if not keep_fast:
            self._fast = None
        # a new cache and lock: a worker still colouring a frame of the old model with
        # its spline (a plugin's may take any time) holds up no frame of the new one
        self._splines = {}
        self._spline_lock = threading.Lock()

    def set_model(self, model: str, options: dict | None = None) -> None:
        """Switch the spline model (``options``: its keyword arguments, e.g. ``k``)."""
        _layer_call(lambda: self.node.update(model=model, **dict(options or {})))

    def set_clip_planes(self, planes) -> None:
        """Clip planes of this layer only (e.g. of its volume), as ``(origin, normal)``
        pairs; frames use them together with the view's planes."""
        from splineviz.core.raycast_reference import normalize_clip_planes

        planes = tuple(tuple(map(tuple, p)) for p in normalize_clip_planes(planes))
        if planes == self.clip_planes:
            return
        self.clip_planes = planes
        self._emit("frame")

    def set_isovalue(self, value) -> None:
        _layer_call(lambda: setattr(self.node, "isovalue", value))

    def set_color(self, color) -> None:
        _layer_call(lambda: setattr(self.node, "color", color))

    def set_opacity(self, opacity) -> None:
        _layer_call(lambda: setattr(self.node, "opacity", opacity))

    def set_material(self, name: str) -> None:
        _layer_call(lambda: setattr(self.node, "material", name))

    def set_color_by(self, field: str, volume: Volume | None = None,
                     reference: tuple | None = None) -> None:
        """Colour the surface by ``field`` (:data:`splineviz.core.colour_by.FIELDS`).

        ``"volume"``: the value of ``volume``'s spline (of this layer's model) at the hits;
        ``"distance"``: the signed distance to the surface ``reference = (volume, model,
        model_options, isovalue)``, e.g. another model or isovalue of the same data.
        """
        _layer_call(lambda: setattr(self.node, "color_by", field))
        if reference is not None:
            from splineviz.core.splines.registry import model_spec

            vol, model, options, iso = reference
            try:
                model_spec(model)
            except SplinevizError as exc:
                raise LayerError(str(exc)) from None
            reference = (vol, model, dict(options or {}), float(iso))
        same_ref = (reference is None and self._color_reference is None) or (
            reference is not None and self._color_reference is not None
            and reference[0] is self._color_reference[0]
            and reference[1:] == self._color_reference[1:])
        if volume is not self._color_volume or not same_ref:
            self._color_volume = volume
            self._color_reference = reference
            self._splines.pop("other", None)
            self._splines.pop("reference", None)
            self._emit("frame")

    def set_color_map(self, name: str | None = None, range_mode: str | None = None,
                      limits=None) -> None:
        """Colour map by name, range mode (``auto``, ``manual``, ``symmetric``) and the
        manual ``(lo, hi)``; only the colouring of shown frames changes, no new ray cast."""
        values = {}
        if name is not None:
            values["color_map"] = name
        if range_mode is not None:
            values["color_range"] = range_mode
        if limits is not None:
            lo, hi = limits
            values.update(color_min=lo, color_max=hi)
            for holds, message in type(self.node).document_rules:
                if not holds({**self.node.model_dump(), **values}):
                    raise LayerError(f"{message}, got {tuple(limits)!r}")
        _layer_call(lambda: self.node.update(values))

    def color_range_of(self, scalars) -> tuple[float, float]:
        """The ``(lo, hi)`` the colour map spans for a frame's ``scalars``."""
        from splineviz.core.colour_by import scalar_range

        values = np.empty(0) if scalars is None else scalars
        return scalar_range(values, self.color_range, *self.color_limits)

    def _spline(self, which: str):
        """This layer's spline (``"own"``), the colour-by volume's (``"other"``) or the
        reference surface's (``"reference"``), built once; the values at the hits come from
        it."""
        from splineviz.plugins import build_spline

        if which not in self._splines:
            if which == "reference":
                vol, model, options, _iso = self._color_reference
                self._splines[which] = build_spline(vol, model, **options)
            else:
                vol = self._volume if which == "own" else self._color_volume
                model, options = self._cast
                self._splines[which] = build_spline(vol, model, **options)
        return self._splines[which]

    def hit_scalars(self, frame: Frame) -> np.ndarray | None:
        """(H, W) colour-by values at the frame's hits (NaN elsewhere), or None.

        Curvatures and the gradient magnitude come from the frame's kernel derivatives when it
        has them (``Frame.hessian``), else from the spline evaluated at the hits."""
        from splineviz.core.colour_by import DERIVATIVE_FIELDS, derivative_scalars, hit_scalars

        color_by = self.color_by
        if color_by == "none":
            return None
        out = np.full(frame.hit.shape, np.nan)
        if color_by in DERIVATIVE_FIELDS and frame.hessian is not None:
            hit = frame.hit
            grad = frame.normal[hit] * frame.gradient_norm[hit][:, None]
            out[hit] = derivative_scalars(color_by, grad, frame.hessian[hit])
            return out
        # the hits are in world; each spline is evaluated in its own volume's frame (the
        # "volume" and "distance" fields read the other spline only)
        pts = frame.position[frame.hit]
        other, other_iso, frame_of = None, 0.0, self._volume
        if color_by == "volume":
            if self._color_volume is None:
                return out
            other, frame_of = self._spline("other"), self._color_volume
        elif color_by == "distance":
            if self._color_reference is None:
                return out
            other, other_iso = self._spline("reference"), self._color_reference[3]
            frame_of = self._color_reference[0]
        out[frame.hit] = hit_scalars(self._spline("own"), from_world(frame_of, pts), color_by,
                                     other, other_iso)
        return out

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible)
        self._emit("appearance")

    # -- frames --------------------------------------------------------------------------

    def _build(self) -> tuple[_Caster, _Caster | None]:
        """(exact caster, preview caster or None), made when missing (uploads the data: in a
        worker, never in the GUI thread). A caster made while the model or the data changed
        is used for this frame only (the frame is then discarded by its state)."""
        from splineviz.compute.raycast import RayCaster

        with self._build_lock:
            generation = self._generation
            exact, fast = self._exact, self._fast
            if exact is None:
                model, options = self._cast
                exact = _Caster(make_caster(self._volume, model, self._device, options))
            if fast is None and exact.path == "bricked":
                # a chunked volume: previews ray cast its coarse level here
                fast = _Caster(exact.rc.preview_caster(), source=exact.rc.preview_label)
            elif fast is None and exact.path != "opencl":
                fast = _Caster(RayCaster(self._volume, model="trilinear", device=self._device))
            if generation == self._generation:
                self._exact, self._fast = exact, fast
            return exact, fast

    def _candidates(self, preview: bool, blocking: bool) -> list[_Caster]:
        """The casters that may make the frame, best first (see :meth:`compute`)."""
        exact, fast = self._exact, self._fast
        if not preview:
            if exact is None and blocking:
                exact, fast = self._build()
            return [] if exact is None else [exact]
        usable = [c for c in (exact, fast)
                  if c is not None and (c is fast or c.path == "opencl")]
        if not usable and blocking:
            exact, fast = self._build()
            usable = [c for c in (exact, fast) if c is fast or c.path == "opencl"]
        if not blocking:
            # the GUI thread casts on the device only: a NumPy-path frame (no OpenCL device)
            # takes the thread for as long as it computes
            usable = [c for c in usable if c.path == "opencl"]
        return usable

    @property
    def coarse_preview(self) -> bool:
        """Whether previews are cast from a coarse level of the data (a chunked volume's,
        :attr:`RenderedFrame.source`): milliseconds at any size, so the one shown while the
        exact bricks are computed is cast at full resolution too."""
        from splineviz.core.chunked import ChunkedVolume

        return isinstance(self._volume, ChunkedVolume)

    def exact_scales(self) -> tuple[float, ...]:
        """The resolution factors a worker casts the exact frame at, one after the other:
        :data:`COARSE_TO_FINE` on the NumPy path (a model without an OpenCL kernel, or no
        device: minutes per frame are possible, so each step is shown and can be given up),
        else one full frame."""
        from splineviz.compute.raycast import family_class
        from splineviz.core.splines.registry import MODELS

        exact = self._exact
        if exact is not None:
            slow = exact.path == "numpy"
        else:
            slow = self._device == "numpy" or (self.node.model in MODELS
                                               and family_class(self.node.model) is None)
        return COARSE_TO_FINE if slow else (1.0,)

    def compute(self, view: ViewState, scale: float = 1.0, preview: bool = False,
                blocking: bool = True, progress=None,
                cancelled=None) -> RenderedFrame | None:
        """Ray cast a frame for ``view`` (thread safe; may take minutes on the NumPy path).

        Parameters
        ----------
        view : ViewState
        scale : float in (0, 1]
            Resolution factor: the frame has ``ceil(scale * size)`` pixels per axis.
        preview : bool
            A preview: the model's own kernel caster at ``scale`` when it has one and it is
            free, else the cheaper preview caster (trilinear, a chunked volume's coarse level,
            or the previous model's kernel right after a switch).
        blocking : bool
            False (the GUI thread): return None instead of waiting for a caster another
            thread uses, building a caster, or evaluating a spline without a kernel for the
            colour-by values (the frame is then uncoloured).
        progress, cancelled : callable, optional
            A chunked volume's exact frame, made in bricks on dask workers: ``progress(done,
            total)`` after each brick; ``cancelled()`` True gives up the frame (None).

        A new isovalue costs nothing here: the ray caster classifies only the cells the rays
        of this frame reach (visible-first), so a reduced-resolution preview of a new
        isovalue is as cheap as any other preview.
        """
        try:
            return self._compute(view, scale, preview, blocking, progress, cancelled)
        except Exception as exc:  # noqa: BLE001 - pyopencl's errors, matched by module
            if not _is_opencl_error(exc) or self._device == "numpy":
                raise
            # out of device memory, a lost device, a driver failure: the NumPy path still
            # gives the exact picture, slowly; say so once instead of dying
            warnings.warn(f"the OpenCL device failed ({' '.join(str(exc).split())[:120]}); "
                          "rendering on the NumPy reference path (slow)", SplinevizWarning,
                          stacklevel=2)
            self._device = "numpy"
            self._drop()
            return self._compute(view, scale, preview, blocking, progress, cancelled)

    def _compute(self, view, scale, preview, blocking, progress, cancelled):
        if not blocking and _WORKERS_ON_DEVICE.busy:
            return None
        candidates = self._candidates(preview, blocking)
        if not blocking:
            # a fallback caster (not this model's own) only at a size it has cast before
            # (a new size compiles the kernel: not in the GUI thread), the largest one not
            # above the one asked for
            candidates = [c for c in candidates
                          if c is self._exact or c.scale_cast(view.size, scale) is not None]
        caster = next((c for i, c in enumerate(candidates)
                       if c.lock.acquire(blocking=blocking and i == 0)), None)
        if caster is None:
            return None
        if not blocking and caster is not self._exact:
            scale = caster.scale_cast(view.size, scale)
        w, h = view.size
        sw, sh = max(1, int(np.ceil(w * scale))), max(1, int(np.ceil(h * scale)))
        try:
            state = self.state
            if caster is not self._exact and caster is not self._fast and not blocking:
                return None  # dropped meanwhile (a worker's frame is judged by its state)
            exact = caster is self._exact or not preview
            rc = caster.rc
            isovalue = self.node.isovalue
            if rc.isovalue != isovalue:
                rc.set_isovalue(isovalue)
            from splineviz.core.colour_by import DERIVATIVE_FIELDS

            # curvature and gradient magnitude from the kernel's derivatives at the hits, when
            # this model's own kernel casts the frame (not a preview caster)
            kernel_derivs = (self.color_by in DERIVATIVE_FIELDS and exact
                             and caster.path == "opencl")
            t = time.perf_counter()
            if caster.path == "bricked":
                extra = {"progress": progress, "cancelled": cancelled}
            else:
                extra = {"hessian": kernel_derivs}
            on_device = blocking and caster.path == "opencl"
            try:
                with _WORKERS_ON_DEVICE if on_device else contextlib.nullcontext():
                    frame = rc.render(view.camera, size=(sw, sh),
                                      clip_planes=tuple(view.clip_planes) + self.clip_planes,
                                      **extra).load()
            except SplinevizError as exc:
                from splineviz.compute.bricked import RenderCancelled

                if isinstance(exc, RenderCancelled):
                    return None
                raise
            seconds = time.perf_counter() - t
            caster.sizes.add((tuple(view.size), scale))
            stats = dict(rc.stats)
        finally:
            caster.lock.release()
        path = stats.get("path", "numpy") if exact else "preview"
        self.last_stats = stats
        scalars = self._scalars(frame, blocking, cheap=path == "preview")
        return RenderedFrame(frame, view, state, min(scale, 1.0), seconds, path, stats,
                             scalars=scalars, model=rc.model,
                             source=caster.source if path == "preview" else "")

    def _scalars(self, frame: Frame, blocking: bool, cheap: bool) -> np.ndarray | None:
        """:meth:`hit_scalars` under the spline cache's lock, or None: for a preview
        (``cheap``) when a spline without a kernel would be evaluated (a plugin's may take
        any time), and in the GUI thread (not ``blocking``) also when the lock is taken or
        a spline must be built."""
        from splineviz.compute.raycast import family_class
        from splineviz.core.colour_by import DERIVATIVE_FIELDS
        from splineviz.core.splines.registry import MODELS

        color_by = self.color_by
        if color_by == "none":
            return None
        if color_by in DERIVATIVE_FIELDS and frame.hessian is not None:
            return self.hit_scalars(frame)  # from the frame alone
        lock = self._spline_lock
        needed = {"own": self._cast[0]}
        if color_by == "volume":
            needed["other"] = self._cast[0]
        elif color_by == "distance" and self._color_reference is not None:
            needed["reference"] = self._color_reference[1]
        for which, model in needed.items():
            if (cheap or not blocking) and (model not in MODELS or family_class(model) is None):
                return None
            if not blocking and which not in self._splines:
                return None
        if blocking:
            with lock:
                return self.hit_scalars(frame)
        if not lock.acquire(blocking=False):
            return None
        try:
            return self.hit_scalars(frame)
        finally:
            lock.release()


def not_projectable(volume) -> str:
    """What of ``volume`` cell projection cannot draw (its tets are laid out on an
    axis-aligned in-memory grid), "" when it can."""
    from splineviz.core.chunked import ChunkedVolume
    from splineviz.core.frame import rotation

    if isinstance(volume, ChunkedVolume):
        return "a chunked volume"
    if rotation(volume) is not None:
        return "an oblique scan"
    return ""


def _layer_call(write):
    """Run ``write`` (a change of a node); a value the node refuses is a :class:`LayerError`
    (the node's own sentence)."""
    try:
        return write()
    except nodes.ModelError as exc:
        raise LayerError(str(exc)) from None


def _is_opencl_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a pyopencl error (matched by module: this layer does not import
    pyopencl itself)."""
    return any(c.__module__.startswith("pyopencl") for c in type(exc).__mro__)
