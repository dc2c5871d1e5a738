"""A volume's direct volume rendering as a layer of the live view (:class:`SplineScene`).

A :class:`VolumeLayer` makes frames of one volume node's volume rendering for a
:class:`~splineviz.render.isosurface.ViewState`, the way
:func:`splineviz.render.volume_rendering.composite_volume_rendering` does for exact pictures
(so that the window and an export agree): the rays end at the window depth of the scene
drawn without the volume rendering (isosurface quads, meshes, outlines), nothing is
composited behind them, and the accumulated colour and opacity are drawn over the picture
(``C + (1 - A) scene``). The scene shows a frame as an RGBA image in an overlay renderer
(window layer 1, so that the depth buffer read at the end of the main renderer's pass is
the scene's alone).

Previews (reduced resolution, the trilinear model) are cast in the GUI thread within the
preview budget; exact frames (full resolution, the node's model) by the refine worker.
Both read the window depth of the last render, so a frame is exact only for the depth it
was cast against (:attr:`VolumeFrame.depth_sig`).
"""

from __future__ import annotations

import contextlib
import threading
import zlib
from dataclasses import dataclass

import numpy as np

from splineviz.render.isosurface import _WORKERS_ON_DEVICE, ViewState

#: the model of previews (the cheapest sampling; bench dvr measures it)
PREVIEW_MODEL = "trilinear"


@dataclass
class VolumeFrame:
    """A volume rendering frame ready to show.

    Attributes
    ----------
    image : (H, W, 4) uint8
        Straight (not premultiplied) colour and opacity, row 0 at the *bottom* (VTK's order),
        at the frame's own size (``scale`` times the view's).
    view : ViewState
    state : tuple
        :attr:`VolumeLayer.state` when it was cast.
    scale : float
    final : bool
        Full resolution with the node's model.
    depth_sig : int
        Signature of the window depth the rays ended at (:func:`depth_signature`).
    path : str
        ``"preview"`` or ``"exact"``.
    """

    image: np.ndarray
    view: ViewState
    state: tuple
    scale: float
    final: bool
    depth_sig: int
    path: str


def depth_signature(depth: np.ndarray) -> int:
    """A checksum of a (H, W) float32 window depth (equal depths, equal signatures)."""
    return zlib.crc32(np.ascontiguousarray(depth, np.float32).data)


def resample_nearest(depth: np.ndarray, w: int, h: int) -> np.ndarray:
    """``depth`` (H0, W0) sampled at the centres of a (h, w) grid over the same window."""
    h0, w0 = depth.shape
    rows = np.minimum(((np.arange(h) + 0.5) * h0 / h).astype(int), h0 - 1)
    cols = np.minimum(((np.arange(w) + 0.5) * w0 / w).astype(int), w0 - 1)
    return depth[rows[:, None], cols[None, :]]


def straight_image(rgba: np.ndarray) -> np.ndarray:
    """(H, W, 4) premultiplied float colour and opacity -> straight uint8, rows flipped to
    VTK's bottom-up order."""
    a = rgba[..., 3:4]
    with np.errstate(divide="ignore", invalid="ignore"):
        rgb = np.where(a > 0.0, rgba[..., :3] / np.maximum(a, 1e-12), 0.0)
    out = np.empty(rgba.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.rint(np.clip(rgb, 0.0, 1.0) * 255.0)
    out[..., 3] = np.rint(np.clip(rgba[..., 3], 0.0, 1.0) * 255.0)
    return out[::-1]


class VolumeLayer:
    """The volume rendering of one volume (see module docstring).

    Parameters
    ----------
    volume : Volume
    name : str
    transfer_function : str or TransferFunctionPoints
        A volume node's :attr:`~splineviz.model.VolumeNode.transfer_function_spec`: a preset
        name, a ParaView JSON file or edited points
        (:func:`~splineviz.model.nodes.resolve_transfer_function`).
    model : str
    shaded : bool
    device : str or None

    Notes
    -----
    :meth:`configure`, :meth:`set_volume` and :meth:`set_clip_planes` only record what the
    next frame is of: a worker casting an exact frame holds the renderers for up to seconds,
    and the GUI thread calls these on every edit (a transfer function dragged in its
    editor). Each cast takes one snapshot of them and brings the renderer it uses up to it.
    """

    def __init__(self, volume, name: str = "volume", transfer_function="ct-bone",
                 model: str = "cubic-c1", shaded: bool = True, device=None):
        self.volume = volume
        self.name = name
        self.transfer_function = transfer_function
        self.model = model
        self.shaded = bool(shaded)
        self.device = device
        self.visible = True
        self.clip_planes: tuple = ()
        self._lock = threading.Lock()
        #: model -> (renderer, (volume id, shaded) it was built for, tf spec it maps with)
        self._renderers: dict[str, tuple] = {}
        self._tf = None
        self._range = None
        #: the models cast so far: the first cast of one builds its kernel (0.5 s and more
        #: on PoCL), which the GUI thread must not wait for; later casts of any size reuse
        #: it (the frame size is a kernel argument)
        self.warm_models: set = set()

    @property
    def state(self) -> tuple:
        """What a frame depends on besides the view and the depth."""
        return self._snapshot()[1]

    def _snapshot(self) -> tuple:
        """(volume, :attr:`state`) read once each (another thread may set them meanwhile)."""
        volume = self.volume
        return volume, (id(volume), self.model, self.transfer_function, self.shaded,
                        self.clip_planes)

    def set_volume(self, volume) -> None:
        self.volume = volume

    def configure(self, transfer_function, model: str, shaded: bool) -> None:
        self.transfer_function = transfer_function
        self.model = model
        self.shaded = bool(shaded)

    def set_clip_planes(self, planes) -> None:
        self.clip_planes = tuple(tuple(map(tuple, p)) for p in planes)

    def _renderer(self, volume, state: tuple, model: str):
        """The renderer of ``model`` for ``volume`` and ``state`` (a :meth:`_snapshot`),
        made or brought up to it (caller holds the lock)."""
        from splineviz.compute.dvr import VolumeRenderer
        from splineviz.model.nodes import resolve_transfer_function

        spec, shaded = state[2], state[3]
        built = (state[0], shaded)
        if self._range is None or self._range[0] != state[0]:
            data = volume.data
            self._range = (state[0], (float(np.min(data)), float(np.max(data))))
            self._tf = None
        if self._tf is None or self._tf[0] != spec:
            self._tf = (spec, resolve_transfer_function(spec, self._range[1]))
        entry = self._renderers.get(model)
        if entry is None or entry[1] != built:
            vr = VolumeRenderer(volume, model, self._tf[1], device=self.device, shaded=shaded)
        else:
            vr = entry[0]
            if entry[2] != spec:
                vr.set_transfer_function(self._tf[1])
        self._renderers[model] = (vr, built, spec)
        return vr

    def is_warm(self, view: ViewState, scale: float) -> bool:
        """Whether a preview (of any size: ``view`` and ``scale`` do not matter) needs no
        kernel build and no per-volume set-up in the caller's thread: the current preview
        renderer has cast before. Previews thus follow the preview scale down when they
        run over their budget (a transfer function dragged on a busy machine)."""
        entry = self._renderers.get(PREVIEW_MODEL)
        return (entry is not None and entry[1] == (id(self.volume), self.shaded)
                and PREVIEW_MODEL in self.warm_models)

    def compute(self, view: ViewState, depth: np.ndarray, depth_sig: int, scale: float = 1.0,
                preview: bool = False, blocking: bool = True) -> VolumeFrame | None:
        """A frame of ``view`` whose rays end at ``depth`` ((H, W) window depth of the
        scene at the view's size, row 0 at the top); None when ``blocking`` is False and
        another thread is casting."""
        from splineviz.compute.dvr import depth_stop

        if not blocking and _WORKERS_ON_DEVICE.busy:
            # a worker's frame (an isosurface's or this one's) holds the device: the GUI
            # thread's kernel would queue behind it for up to a second
            return None
        if not self._lock.acquire(blocking=blocking):
            return None
        on_device = _WORKERS_ON_DEVICE if blocking else contextlib.nullcontext()
        try:
            volume, state = self._snapshot()
            model = PREVIEW_MODEL if preview else state[1]
            w, h = _scaled(view.size, scale)
            d = depth if (w, h) == tuple(view.size)[:2] else resample_nearest(depth, w, h)
            camera = view.camera
            stop = depth_stop(d, np.zeros((h, w, 3), np.uint8), camera,
                              camera.clipping_range)
            stop[1][..., 3] = 0.0  # the scene's colour is composited below, by blending
            planes = list(view.clip_planes) + list(state[4])
            with on_device:
                vr = self._renderer(volume, state, model)
                frame = vr.render(camera, (w, h), clip_planes=planes, stop=stop)
            self.warm_models.add(model)
        finally:
            self._lock.release()
        final = not preview and (w, h) == tuple(view.size)[:2]
        return VolumeFrame(straight_image(frame.rgba), view, state, float(scale), final,
                           int(depth_sig), "preview" if preview else "exact")

    def close(self) -> None:
        with self._lock:
            self._renderers.clear()


def _scaled(size, scale: float) -> tuple[int, int]:
    return max(int(round(size[0] * scale)), 1), max(int(round(size[1] * scale)), 1)
