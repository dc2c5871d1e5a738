"""An isosurface layer: the state of one ray-cast spline isosurface, free of any view.

A layer holds the volume, the spline model, the isovalue, the appearance (colour, opacity,
material) and the ray casters that make its frames. Views (:class:`~splineviz.render.scene.
SplineScene`) ask it for frames of *their* camera and size with :meth:`IsosurfaceLayer.compute`
and show them with a :class:`~splineviz.render.quad.FrameQuad`; several views (the window,
an off-screen export) can show one layer. ``compute`` may run in a worker thread: the ray
casters are guarded by a lock.

Preview: tetrahedral models without an OpenCL kernel render through the NumPy reference
(seconds per frame). While the camera moves, a layer can render a *preview* at reduced
resolution, with the trilinear OpenCL kernel when its own model has none (same data, same
isovalue; the surfaces differ by the model error only); the exact frame follows when the
interaction ends (thesis §6.3: interactive rates for the trilinear model, exact pictures for
the smooth ones).
"""

from __future__ import annotations

import threading
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from splineviz.core.camera import Camera
from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.core.material import MATERIALS, Material
from splineviz.core.raycast_reference import Frame
from splineviz.core.splines import MODELS
from splineviz.core.volume import Volume
from splineviz.model import nodes

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


class IsosurfaceLayer:
    """One spline isosurface of a volume (see module docstring).

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
    """

    def __init__(self, volume: Volume, model: str = "trilinear", isovalue=None,
                 color=PALETTE[0], opacity: float = 1.0, name: str = "isosurface",
                 device: str | None = None, material: str = "default", model_options=None):
        self._check_model(model)
        self.name = name
        self.visible = True
        self._device = device
        # one lock per caster: a preview (GUI thread) never waits for an exact frame that a
        # worker thread is computing with the other caster
        self._lock = threading.RLock()
        self._preview_lock = threading.RLock()
        self._listeners = []
        self._volume = volume
        self._model = model
        self._model_options = dict(model_options or {})
        #: clip planes of this layer alone, added to the view's (see :meth:`set_clip_planes`)
        self.clip_planes: tuple = ()
        self._version = 0
        self._caster = None
        self._preview = None
        self.color = tuple(float(c) for c in color)
        self.opacity = 1.0
        self.set_opacity(opacity)
        self.material_name = "default"
        self.set_material(material)
        self._isovalue = (0.5 * sum(volume.finite_range) if isovalue is None
                          else float(isovalue))
        self.last_stats: dict = {}
        #: colour by (core.colour_by.FIELDS), its map, range mode and manual limits
        self.color_by = "none"
        self.color_map = "viridis"
        self.color_range = "auto"
        self.color_limits = (0.0, 1.0)
        self._color_volume: Volume | None = None
        self._color_reference: tuple | None = None  # (volume, model, options, isovalue)
        self._splines: dict = {}  # "own" / "other" -> Spline for the colour-by values

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

    # -- state ---------------------------------------------------------------------------

    @property
    def volume(self) -> Volume:
        return self._volume

    @property
    def model(self) -> str:
        return self._model

    @property
    def isovalue(self) -> float:
        return self._isovalue

    @property
    def state(self) -> tuple:
        """Changes whenever frames of this layer must be recomputed."""
        return (self._version, self._model, self._isovalue)

    def set_volume(self, volume: Volume) -> None:
        """New data (e.g. smoothed); keeps model and isovalue.

        The casters are dropped, not updated: uploading the data and classifying belong in
        the thread that makes the next exact frame, and a frame a worker is still making
        from the old casters is discarded when it arrives (:meth:`compute` checks). Nothing
        here waits for a lock, so the GUI thread never waits for a ray cast.
        """
        self._volume = volume
        self._caster = None
        self._preview = None
        self._splines = {}
        self._emit("frame")

    @staticmethod
    def _check_model(model: str) -> None:
        if model not in MODELS:
            raise LayerError(f"unknown spline model {model!r}; choose one of {list(MODELS)}")

    def set_model(self, model: str, options: dict | None = None) -> None:
        """Switch the spline model (``options``: its keyword arguments, e.g. ``k``)."""
        self._check_model(model)
        options = dict(options or {})
        if model == self._model and options == self._model_options:
            return
        # as in set_volume: drop the casters without waiting for a worker that uses them
        self._model = model
        self._model_options = options
        self._caster = None
        self._preview = None
        self._splines = {}
        self._emit("frame")

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
        value = float(value)
        if not np.isfinite(value):
            raise LayerError(f"the isovalue must be finite, got {value}")
        if value == self._isovalue:
            return
        self._isovalue = value  # classification happens lazily, in compute()
        self._emit("frame")

    def set_color(self, color) -> None:
        c = tuple(float(v) for v in color)
        if len(c) != 3 or not all(0.0 <= v <= 1.0 for v in c):
            raise LayerError(f"a colour is three numbers in [0, 1], got {color!r}")
        self.color = c
        self._emit("appearance")

    def set_opacity(self, opacity) -> None:
        o = float(opacity)
        if not 0.0 < o <= 1.0:
            raise LayerError(f"opacity must be in (0, 1], got {opacity}")
        self.opacity = o
        self._emit("appearance")

    def set_material(self, name: str) -> None:
        if name not in MATERIALS:
            raise LayerError(f"unknown material {name!r}; choose one of {list(MATERIALS)}")
        self.material_name = name
        self._emit("appearance")

    def set_color_by(self, field: str, volume: Volume | None = None,
                     reference: tuple | None = None) -> None:
        """Colour the surface by ``field`` (:data:`splineviz.core.colour_by.FIELDS`).

        ``"volume"``: the value of ``volume``'s spline (of this layer's model) at the hits;
        ``"distance"``: the signed distance to the surface ``reference = (volume, model,
        model_options, isovalue)``, e.g. another model or isovalue of the same data.
        """
        from splineviz.core.colour_by import FIELDS

        if field not in FIELDS:
            raise LayerError(f"unknown colour-by field {field!r}; choose one of "
                             f"{', '.join(FIELDS)}")
        if reference is not None:
            vol, model, options, iso = reference
            self._check_model(model)
            reference = (vol, model, dict(options or {}), float(iso))
        same_ref = (reference is None and self._color_reference is None) or (
            reference is not None and self._color_reference is not None
            and reference[0] is self._color_reference[0]
            and reference[1:] == self._color_reference[1:])
        if field == self.color_by and volume is self._color_volume and same_ref:
            return
        self.color_by = field
        self._color_volume = volume
        self._color_reference = reference
        self._splines.pop("other", None)
        self._splines.pop("reference", None)
        self._emit("frame")

    def set_color_map(self, name: str | None = None, range_mode: str | None = None,
                      limits=None) -> None:
        """Colour map by name, range mode (``auto``, ``manual``, ``symmetric``) and the
        manual ``(lo, hi)``; only the colouring of shown frames changes, no new ray cast."""
        from splineviz.core.colour_by import RANGE_MODES
        from splineviz.render.colormaps import ColormapError, lut

        if name is not None:
            try:
                lut(name)
            except ColormapError as exc:
                raise LayerError(str(exc)) from None
            self.color_map = name
        if range_mode is not None:
            if range_mode not in RANGE_MODES:
                raise LayerError(f"unknown range mode {range_mode!r}; choose one of "
                                 f"{', '.join(RANGE_MODES)}")
            self.color_range = range_mode
        if limits is not None:
            lo, hi = (float(v) for v in limits)
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise LayerError(f"a colour range needs finite lo < hi, got {limits!r}")
            self.color_limits = (lo, hi)
        self._emit("appearance")

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
                self._splines[which] = build_spline(vol, self._model, **self._model_options)
        return self._splines[which]

    def hit_scalars(self, frame: Frame) -> np.ndarray | None:
        """(H, W) colour-by values at the frame's hits (NaN elsewhere), or None.

        Curvatures and the gradient magnitude come from the frame's kernel derivatives when it
        has them (``Frame.hessian``), else from the spline evaluated at the hits."""
        from splineviz.core.colour_by import DERIVATIVE_FIELDS, derivative_scalars, hit_scalars

        if self.color_by == "none":
            return None
        out = np.full(frame.hit.shape, np.nan)
        if self.color_by in DERIVATIVE_FIELDS and frame.hessian is not None:
            hit = frame.hit
            grad = frame.normal[hit] * frame.gradient_norm[hit][:, None]
            out[hit] = derivative_scalars(self.color_by, grad, frame.hessian[hit])
            return out
        pts = frame.position[frame.hit]
        other, other_iso = None, 0.0
        if self.color_by == "volume":
            if self._color_volume is None:
                return out
            other = self._spline("other")
        elif self.color_by == "distance":
            if self._color_reference is None:
                return out
            other, other_iso = self._spline("reference"), self._color_reference[3]
        out[frame.hit] = hit_scalars(self._spline("own"), pts, self.color_by, other, other_iso)
        return out

    @property
    def material(self) -> Material:
        return MATERIALS[self.material_name]

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible)
        self._emit("appearance")

    # -- frames --------------------------------------------------------------------------

    def _casters(self, build: bool = True):
        """(exact caster, trilinear preview caster or None); (None, None) when they do not
        exist yet and ``build`` is False (building uploads the data: not in the GUI thread)."""
        from splineviz.compute.raycast import RayCaster

        if not build:
            # read without the lock: a worker holds it for a whole exact frame, and the GUI
            # thread's preview waited for it (170 ms when a split view's first view was
            # repainted at half width while its exact frame was being cast). The builder
            # makes both casters under the lock; until it has, there is no preview.
            exact, fast = self._caster, self._preview
            if exact is None or (fast is None and exact.stats.get("path") != "opencl"):
                return None, None
            return exact, fast
        with self._lock:
            if self._caster is None:
                self._caster = make_caster(self._volume, self._model, self._device,
                                           self._model_options)
            if self._caster.stats.get("path") == "bricked" and self._preview is None:
                # a chunked volume: previews ray cast its coarse level here
                self._preview = self._caster.preview_caster()
            elif self._caster.stats.get("path") != "opencl" and self._preview is None:
                self._preview = RayCaster(self._volume, model="trilinear", device=self._device)
            return self._caster, self._preview

    @property
    def exact_path(self) -> str:
        """``"opencl"`` or ``"numpy"``: how exact frames of this layer are made."""
        return self._casters()[0].stats.get("path", "numpy")

    def compute(self, view: ViewState, scale: float = 1.0, preview: bool = False,
                blocking: bool = True, progress=None,
                cancelled=None) -> RenderedFrame | None:
        """Ray cast a frame for ``view`` (thread safe; may take seconds on the NumPy path).

        Parameters
        ----------
        view : ViewState
        scale : float in (0, 1]
            Resolution factor: the frame has ``ceil(scale * size)`` pixels per axis.
        preview : bool
            Use the fast trilinear OpenCL caster when this model has no kernel.
        blocking : bool
            If False, return None instead of waiting while another thread uses the caster
            or instead of building the casters (the GUI thread's previews).
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
            with self._lock, self._preview_lock:
                self._device = "numpy"
                self._caster = self._preview = None
            return self._compute(view, scale, preview, blocking, progress, cancelled)

    def _compute(self, view, scale, preview, blocking, progress, cancelled):
        w, h = view.size
        sw, sh = max(1, int(np.ceil(w * scale))), max(1, int(np.ceil(h * scale)))
        exact, fast = self._casters(build=blocking)
        if exact is None:
            return None
        use_fast = preview and fast is not None
        rc, lock = (fast, self._preview_lock) if use_fast else (exact, self._lock)
        if not lock.acquire(blocking=blocking):
            return None
        try:
            state = self.state
            if rc is not (self._preview if use_fast else self._caster):
                return None  # the model changed meanwhile
            if rc.isovalue != self._isovalue:
                rc.set_isovalue(self._isovalue)
            from splineviz.core.colour_by import DERIVATIVE_FIELDS

            # curvature and gradient magnitude from the kernel's derivatives at the hits, when
            # this model's own kernel casts the frame (not the trilinear preview caster)
            kernel_derivs = (self.color_by in DERIVATIVE_FIELDS and rc is exact
                             and exact.stats.get("path") == "opencl")
            t = time.perf_counter()
            if rc.stats.get("path") == "bricked":
                extra = {"progress": progress, "cancelled": cancelled}
            else:
                extra = {"hessian": kernel_derivs}
            try:
                frame = rc.render(view.camera, size=(sw, sh),
                                  clip_planes=tuple(view.clip_planes) + self.clip_planes,
                                  **extra).load()
            except SplinevizError as exc:
                from splineviz.compute.bricked import RenderCancelled

                if isinstance(exc, RenderCancelled):
                    return None
                raise
            seconds = time.perf_counter() - t
            stats = dict(rc.stats)
        finally:
            lock.release()
        path = "preview" if rc is not exact else stats.get("path", "numpy")
        self.last_stats = stats
        # colour-by values from the spline's exact derivatives at the hits (per hit, no pass
        # over the volume); under the caster lock: the spline cache is shared
        with self._lock:
            scalars = self.hit_scalars(frame)
        return RenderedFrame(frame, view, state, min(scale, 1.0), seconds, path, stats,
                             scalars=scalars)


def _is_opencl_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a pyopencl error (matched by module: this layer does not import
    pyopencl itself)."""
    return any(c.__module__.startswith("pyopencl") for c in type(exc).__mro__)
