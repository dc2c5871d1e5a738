"""Out-of-core, distributed ray casting of chunked volumes: bricks on dask workers, composited
sort-last on the client (exact: the same first hits, depths and colours as one ray caster).

A :class:`BrickedRayCaster` cuts the volume into bricks (:mod:`splineviz.core.bricks`) with
the ghost layers its spline model reads, so each brick's spline on its own box is the global
spline. Per frame every brick that may hold the surface is sent to a dask worker
(:func:`render_brick`): it reads its samples (only its box plus halo, never the volume),
builds a :class:`~splineviz.compute.raycast.RayCaster` on them (kept in a per-worker cache
for later frames), and ray casts the pixels of the brick's screen footprint in the *whole*
volume's coordinates, restricted to the cells the brick owns
(:class:`~splineviz.core.bricks.Placement`): the same eye, entry points, clipping range and
clip planes as one ray caster of the whole volume, and the same cell boundaries and
polynomials in every cell, so each brick's first hits are that caster's, bit for bit. The
client composites the returned fragments (:mod:`splineviz.core.compositing`): least depth for
opaque surfaces, back-to-front brick order for translucent ones.

A volume with a direction (an oblique scan) is cast in its own axis-aligned frame: the camera
and clip planes are moved there once, when a frame starts, every brick is cast and composited
there (its samples are an axis-aligned box of that frame, :meth:`ChunkedVolume.read`), and the
composite is turned into world once (:mod:`splineviz.core.frame`; a rigid map keeps window
depths, so hidden-brick culling and compositing need no change). The coarse preview keeps the
direction (:meth:`ChunkedVolume.preview_volume`) and its ray caster moves the world camera
itself.

Work skipped, exactly:

* *empty bricks*: each rendered brick reports conservative bounds of its spline (the root of
  its min-max octree); at any later isovalue outside them the brick is not read again.
  :meth:`BrickedRayCaster.summarize` computes such bounds for every brick in one pass.
* *hidden bricks*: bricks go out front to back with a bounded number in flight; a brick
  whose screen footprint already shows hits nearer than its nearest point is not rendered.

Workers: a ``dask.distributed`` LocalCluster on this machine by default, or any scheduler
(``tcp://host:8786``). A coarse level (OME-Zarr multiscale, an analytic pyramid) is ray cast
locally first, as a preview, while the bricks are computed (:meth:`BrickedRayCaster.frames`).
"""

from __future__ import annotations

import os
import threading
import time
import weakref
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from splineviz.compute.raycast import RayCaster, RayCastError, renders_in_bricks
from splineviz.core import frame as volume_frame
from splineviz.core.bricks import (
    BrickGrid,
    Placement,
    occluded,
    screen_footprint,
    value_margin,
)
from splineviz.core.camera import Camera, parse_size
from splineviz.core.chunked import ChunkedVolume
from splineviz.core.compositing import Composite, Fragment
from splineviz.core.raycast_reference import Frame, normalize_clip_planes
from splineviz.core.splines.registry import MODELS, model_spec
from splineviz.core.volume import Volume

#: cells per brick along each axis when none is given (bricks of whole chunks, about 256^3)
BRICK_CELLS = 256
#: bytes of brick ray casters (samples and device buffers, :func:`caster_bytes`) a worker
#: keeps for later frames (``$SPLINEVIZ_BRICK_CACHE``)
WORKER_CACHE_BYTES = int(float(os.environ.get("SPLINEVIZ_BRICK_CACHE", 2**30)))
#: bricks in flight per worker (more: better load balance; fewer: more hidden bricks culled)
INFLIGHT_PER_WORKER = 2


class RenderCancelled(RayCastError):
    """A bricked frame given up for a newer one (:meth:`BrickedRayCaster.render`)."""


def default_brick_size(chunks, target: int | None = None) -> tuple[int, int, int]:
    """Cells per brick: the largest whole number of storage chunks up to ``target`` per axis
    (default :data:`BRICK_CELLS`; a brick's halo then reads into its neighbours' chunks on
    its faces only)."""
    target = BRICK_CELLS if target is None else target
    return tuple(max(c, (target // c) * c) for c in chunks)


# -- workers ------------------------------------------------------------------------------

_cache: OrderedDict = OrderedDict()
_cache_lock = threading.Lock()


def caster_bytes(rc) -> int:
    """Memory a ray caster holds: its samples (in their own type: 1 byte each for uint8) and,
    on the OpenCL path, its device buffers (host memory on a CPU device; the larger part)."""
    n = rc.volume.data.nbytes
    if rc.stats.get("path") == "opencl":
        n += sum(rc.limits().need.values())
    return n


def _cached_caster(key, make, budget: int):
    """A brick's ray caster from this worker's LRU cache (``budget`` bytes,
    :func:`caster_bytes`), or ``make()`` it. Returns (caster, seconds to make it, whether it
    was cached)."""
    with _cache_lock:
        rc = _cache.get(key)
        if rc is not None:
            _cache.move_to_end(key)
            return rc, 0.0, True
    t = time.perf_counter()
    rc = make()
    seconds = time.perf_counter() - t
    with _cache_lock:
        size = caster_bytes(rc)
        if size <= budget:
            _cache[key] = rc
            while sum(caster_bytes(c) for c in _cache.values()) > budget:
                _cache.popitem(last=False)
    return rc, seconds, False


@dataclass(frozen=True)
class BrickTask:
    """What a worker needs to render one brick (small: the volume travels separately)."""

    token: str
    index: tuple
    read: tuple
    model: str
    model_kwargs: tuple
    device: str | None
    isovalue: float
    camera: Camera
    size: tuple
    planes: tuple
    cache_bytes: int
    #: pixels cast: (r0, r1, c0, c1) of the frame, the brick's screen footprint
    window: tuple
    #: the brick in the whole volume (its rays are the whole volume's)
    placement: Placement


def render_brick(volume, task: BrickTask) -> Fragment:
    """Ray cast one brick (runs on a worker).

    Parameters
    ----------
    volume : ChunkedVolume or Volume
    task : BrickTask

    Returns
    -------
    Fragment
        The brick's hits; ``stats``: ``read_s``, ``build_s`` (upload and octree), ``render_s``
        seconds, ``cached``, ``bounds`` (conservative spline bounds over the brick),
        ``pixels`` (of its window) and ``worker`` (process id).
    """
    timing = {"read_s": 0.0}

    def make():
        t = time.perf_counter()
        if isinstance(volume, ChunkedVolume):
            vol = volume.read(task.read)
        else:
            sl = tuple(slice(a, b) for a, b in task.read)
            vol = Volume(volume.data[sl], volume.spacing,
                         tuple(o + a * s for o, (a, _), s in zip(
                             volume.origin, task.read, volume.spacing, strict=True)))
        timing["read_s"] = time.perf_counter() - t
        return RayCaster(vol, model=task.model, device=task.device, **dict(task.model_kwargs))

    # the samples read (not the brick's index, which another grid of the volume reuses)
    key = (task.token, task.read, task.model, task.model_kwargs, task.device)
    rc, build_s, cached = _cached_caster(key, make, task.cache_bytes)
    # one frame at a time per caster (threads of one worker process share the cache)
    with _caster_lock(rc):
        rc.set_isovalue(task.isovalue)
        frame = rc.render(task.camera, size=task.size, clip_planes=task.planes,
                          window=task.window, placement=task.placement)
        render_s = rc.stats["render_s"]
        bounds = rc.value_bounds() if rc.stats.get("path") == "opencl" else None
    r0, r1, c0, c1 = task.window
    return Fragment.from_frame(task.index, frame, {
        "read_s": timing["read_s"], "build_s": build_s - timing["read_s"] if not cached else 0.0,
        "render_s": render_s, "cached": cached, "bounds": bounds, "worker": os.getpid(),
        "device": rc.stats.get("device"), "pixels": (r1 - r0) * (c1 - c0)}, offset=(r0, c0))


_locks = weakref.WeakKeyDictionary()


def _caster_lock(rc) -> threading.Lock:
    """The lock of one brick caster (gone with the caster when the cache drops it)."""
    with _cache_lock:
        return _locks.setdefault(rc, threading.Lock())


# -- cluster ------------------------------------------------------------------------------

_local = {}

#: defaults of casters made without explicit settings (the CLI's ``--scheduler``,
#: ``--workers``, progress bar and brick cache; ``$SPLINEVIZ_SCHEDULER``)
DEFAULTS = {"scheduler": os.environ.get("SPLINEVIZ_SCHEDULER") or None, "workers": None,
            "progress": None, "cache_bytes": WORKER_CACHE_BYTES}


def configure(**settings) -> None:
    """Set :data:`DEFAULTS`: ``scheduler`` (``tcp://host:port`` or None for a
    LocalCluster), ``workers`` (LocalCluster size), ``progress`` (``progress(done, total)``
    called after each brick of every frame), ``cache_bytes`` (brick casters a worker keeps
    for later frames; 0 for a single frame)."""
    unknown = set(settings) - set(DEFAULTS)
    if unknown:
        raise TypeError(f"unknown bricked rendering settings: {', '.join(sorted(unknown))}")
    DEFAULTS.update(settings)


def get_client(scheduler: str | None = None, workers: int | None = None,
               processes: bool = True):
    """A ``dask.distributed`` client: of the scheduler at ``scheduler`` (``tcp://host:port``),
    else of a LocalCluster on this machine started once per process (``workers`` processes
    of one thread each; default: one per core, at most 4).

    Raises
    ------
    RayCastError
        When the scheduler cannot be reached.
    """
    from distributed import Client, LocalCluster

    if scheduler:
        client = _local.get(scheduler)
        if client is None or client.status != "running":
            try:
                client = Client(scheduler, timeout="10s")
            except (OSError, TimeoutError) as exc:
                raise RayCastError(f"cannot reach the dask scheduler {scheduler}: "
                                   f"{exc}") from None
            _local[scheduler] = client
        return client
    n = workers or max(1, min(4, os.cpu_count() or 1))
    key = (n, processes)
    client = _local.get(key)
    if client is None or client.status != "running":
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                               dashboard_address=":0")
        client = Client(cluster)
        _local[key] = client
    return client


def close_clients() -> None:
    """Close the clients (and LocalClusters) :func:`get_client` opened, e.g. when a command
    ends: their workers' data go without errors in the log."""
    while _local:
        _, client = _local.popitem()
        cluster = client.cluster
        client.close()
        if cluster is not None:
            cluster.close()


# -- the caster ---------------------------------------------------------------------------


class BrickedRayCaster:
    """Ray caster of a volume in bricks on dask workers (module docstring); the interface of
    :class:`~splineviz.compute.raycast.RayCaster`: :meth:`set_isovalue`, :meth:`render`,
    ``stats``.

    Parameters
    ----------
    volume : ChunkedVolume or Volume
    model : str
    device : str or None
        OpenCL device preference on the workers.
    client : distributed.Client, optional
        Default: :func:`get_client` (``scheduler``, ``workers``).
    scheduler : str, optional
        ``tcp://host:port`` of a dask scheduler.
    workers : int, optional
        Workers of the LocalCluster started when there is neither client nor scheduler.
    brick_size : int or (3,) int, optional
        Cells per brick (default :func:`default_brick_size`).
    bricks : int or (3,) int, optional
        Number of bricks per axis instead of ``brick_size``.
    cull : bool
        Skip bricks hidden behind hits already composited (opaque; exact).
    cache_bytes : int, optional
        Bytes of brick ray casters kept per worker for later frames (:func:`caster_bytes`;
        default ``DEFAULTS["cache_bytes"]``).
    **model_kwargs
        Passed to the brick ray casters (e.g. ``k``).

    Examples
    --------
    >>> import numpy as np, dask.array as da, splineviz as sv  # doctest: +SKIP
    >>> vol = sv.Volume.from_dask(da.random.random((256, 256, 256), chunks=64))  # doctest: +SKIP
    >>> rc = BrickedRayCaster(vol, model="trilinear", bricks=2)  # doctest: +SKIP
    >>> rc.set_isovalue(0.5); frame = rc.render(cam, size=(320, 240))  # doctest: +SKIP
    """

    def __init__(self, volume, model: str = "cubic-c1", device: str | None = None, *,
                 client=None, scheduler: str | None = None, workers: int | None = None,
                 brick_size=None, bricks=None, cull: bool = True,
                 cache_bytes: int | None = None, **model_kwargs):
        from dask.base import tokenize

        spec = model_spec(model)
        if not renders_in_bricks(model):
            # only the kernel families whose bricks carry the same spline declare how far
            # their stencils reach; a model may be global (an interpolating B-spline's
            # prefilter reads the whole volume)
            raise RayCastError(f"the {model} model cannot be rendered in bricks; choose one "
                               f"of {', '.join(m for m in MODELS if renders_in_bricks(m))}")
        if not isinstance(volume, ChunkedVolume | Volume):
            volume = Volume(volume)
        self.model = model
        self.device = device
        self._model_kwargs = tuple(sorted(model_kwargs.items()))
        self._volume = volume
        halo, align, centred = spec.ghost_layers, spec.lattice_period, spec.centred_cells
        if bricks is not None:
            self.grid = BrickGrid.split(volume.shape, bricks, halo, align, centred)
        else:
            chunks = volume.chunks if isinstance(volume, ChunkedVolume) else volume.shape
            self.grid = BrickGrid(volume.shape, brick_size or default_brick_size(chunks), halo,
                                  align, centred)
        self.cull = bool(cull)
        self.cache_bytes = int(DEFAULTS["cache_bytes"] if cache_bytes is None else cache_bytes)
        self._client = client
        self._scheduler = scheduler
        self._workers = workers
        self._shared = None
        self._token = tokenize(volume.data if isinstance(volume, ChunkedVolume) else
                               np.asarray(volume.data), volume.spacing, volume.origin)
        self._isovalue = None
        #: conservative spline bounds per brick index, as reported by workers or summarize()
        self.brick_bounds: dict = {}
        self._preview = None
        self._pending = []
        self.stats = {"path": "bricked", "device": device, "bricks": len(self.grid),
                      "classify_s": None, "render_s": None, "active_cells": None,
                      "active_tets": None, "classified": None}

    # -- state -------------------------------------------------------------------------

    @property
    def volume(self):
        return self._volume

    @property
    def isovalue(self):
        return self._isovalue

    @property
    def client(self):
        if self._client is None:
            self._client = get_client(self._scheduler or DEFAULTS["scheduler"],
                                      self._workers or DEFAULTS["workers"])
        return self._client

    def preview_caster(self, model: str = "trilinear") -> RayCaster:
        """A ray caster of the coarse level in memory (:meth:`ChunkedVolume.preview_volume`:
        the same world box) for the pictures shown while the bricks are computed and while
        the camera moves (an in-memory volume: the volume itself)."""
        vol = self._volume
        if isinstance(vol, ChunkedVolume):
            vol = vol.preview_volume()
        options = dict(self._model_kwargs) if model == self.model else {}
        return RayCaster(vol, model=model, device=self.device, **options)

    @property
    def preview_label(self) -> str:
        """What :meth:`preview_caster` casts, in words (``"coarse level 2 of 3 (128^3 of
        512^3)"``; empty for an in-memory volume)."""
        vol = self._volume
        return vol.preview_level().label if isinstance(vol, ChunkedVolume) else ""

    def set_isovalue(self, value) -> None:
        """Set the isovalue (constant time: bricks are classified where they are rendered)."""
        value = float(value)
        if not np.isfinite(value):
            raise RayCastError(f"the isovalue must be finite, got {value}")
        self._isovalue = value
        self.stats["classify_s"] = 0.0

    def _volume_future(self):
        """The volume (its dask graph or samples) on every worker, sent once."""
        if self._shared is None or self._shared[0] is not self.client:
            fut = self.client.scatter(self._volume, broadcast=True, hash=False)
            self._shared = (self.client, fut)
        return self._shared[1]

    def summarize(self) -> dict:
        """Conservative spline bounds of every brick from one pass over the data (dask
        min/max of each read box on the workers, widened by the ghosts and the model's
        negative weights); later isovalues outside them skip the brick unread.

        Returns
        -------
        dict brick index -> (lo, hi)
        """
        boxes = list(self.grid)
        if isinstance(self._volume, ChunkedVolume):
            reds = []
            for b in boxes:
                sub = self._volume.data[tuple(slice(a, e) for a, e in b.read)]
                reds += [sub.min(), sub.max()]
            values = self.client.compute(reds, sync=True)
        else:  # the samples are here already: no need to ship them anywhere
            values = []
            for b in boxes:
                sub = self._volume.data[tuple(slice(a, e) for a, e in b.read)]
                values += [sub.min(), sub.max()]
        mass = _negative_mass(self.model, self.device, dict(self._model_kwargs))
        ghost = model_spec(self.model).ghost_layers
        for n, b in enumerate(boxes):
            lo, hi = float(values[2 * n]), float(values[2 * n + 1])
            self.brick_bounds[b.index] = value_margin(
                lo, hi, ghost, mass, b.touches_boundary(self.grid.shape))
        return dict(self.brick_bounds)

    # -- frames ------------------------------------------------------------------------

    def render(self, camera: Camera, size=(640, 480), clip_planes=(),
               composite: str = "nearest", progress=None, cancelled=None) -> Frame:
        """Ray cast one exact frame (all bricks).

        Parameters
        ----------
        camera : Camera
        size : (width, height) or "WxH"
        clip_planes : sequence of (origin, normal)
        composite : {"nearest", "back-to-front"}
            Least depth per pixel as fragments arrive (opaque), or painting in back-to-front
            brick order once all arrived (translucent layers).
        progress : callable, optional
            ``progress(done, total)`` after each brick.
        cancelled : callable, optional
            Asked after each brick; True (e.g. the camera moved on) cancels the bricks still
            out and raises :class:`RenderCancelled`.
        """
        frame = None
        progress = progress or DEFAULTS["progress"]
        frames = self.frames(camera, size, clip_planes, composite, preview=False)
        for stage, done, total, f in frames:
            if progress is not None and stage != "preview":
                progress(done, total)
            if cancelled is not None and stage == "bricks" and cancelled():
                frames.close()  # cancels what is still out
                raise RenderCancelled("the frame was cancelled before its bricks arrived")
            frame = f
        return frame

    def cancel(self) -> None:
        """Cancel the brick tasks of the frame being made (a newer camera supersedes it)."""
        pending, self._pending = self._pending, []
        if pending:
            self.client.cancel(pending)

    def frames(self, camera: Camera, size=(640, 480), clip_planes=(), composite="nearest",
               preview: bool = True):
        """Frames of increasing quality: ``(stage, done, total, frame)`` with stage
        ``"preview"`` (the coarse level, ray cast here at once; only when the volume has
        one), then ``"bricks"`` after each brick arrives, the last one ``"exact"``.

        ``frame`` of a ``"bricks"`` stage is a live view of the composite (copy it to keep
        it). Closing the generator early cancels the outstanding brick tasks.
        """
        from distributed import as_completed

        if self._isovalue is None:
            raise RayCastError("set an isovalue before rendering")
        if not isinstance(camera, Camera):
            raise RayCastError("render needs a splineviz Camera")
        if composite not in ("nearest", "back-to-front"):
            raise RayCastError(f"composite must be 'nearest' or 'back-to-front', got "
                               f"{composite!r}")
        w, h = parse_size(size)
        t_start = time.perf_counter()
        vol = self._volume
        world_planes = normalize_clip_planes(clip_planes)
        # the bricks are cast in the volume's own frame (module notes): camera and planes
        # moved there once, the composite moved back once
        inside = volume_frame.camera_to_volume(vol, camera)
        # one clipping range for every brick: the whole volume's, so window depths agree
        clip = inside.fit_clipping_range(vol.bounds)
        cam = Camera(inside.position, inside.focal_point, inside.view_up, inside.view_angle,
                     clip)
        user = [tuple(map(tuple, p)) for p in volume_frame.planes_to_volume(vol, world_planes)]
        self.stats.update(preview_s=None, brick_times=[])
        if preview and isinstance(vol, ChunkedVolume) and vol.levels:
            t = time.perf_counter()
            # the preview volume keeps the direction: its caster takes the world camera
            coarse = self._render_preview(
                Camera(camera.position, camera.focal_point, camera.view_up, camera.view_angle,
                       clip), (w, h), world_planes)
            self.stats["preview_s"] = time.perf_counter() - t
            yield "preview", 0, len(self.grid), coarse
        order = self.grid.visibility_order(cam.position, vol.spacing, vol.origin)
        empty = {b.index for b in order if b.index in self.brick_bounds
                 and not (self.brick_bounds[b.index][0] <= self._isovalue
                          <= self.brick_bounds[b.index][1])}
        todo = [b for b in order if b.index not in empty]
        # each brick casts only the pixels its box can cover (and is skipped when off screen)
        foot = {b.index: screen_footprint(cam, self.grid.world_box(b, vol.spacing, vol.origin),
                                          (w, h), clip) for b in todo}
        total = len(todo)
        comp = Composite((w, h))
        shared = self._volume_future()
        client = self.client
        nworkers = max(1, len(client.scheduler_info(n_workers=-1)["workers"]))
        limit = INFLIGHT_PER_WORKER * nworkers
        # opaque composites can drop hidden bricks; painting back to front needs them all
        cull = self.cull and composite == "nearest"
        fragments, culled, t_comp = [], [], 0.0
        steps = self.grid.slab_steps(cam.position, vol.spacing, vol.origin)
        pending = as_completed()
        self._pending = []
        inflight = {}  # future key -> brick
        queue = list(todo)
        done = 0
        try:
            while queue or self._pending:
                while queue and len(self._pending) < limit:
                    n = self._next_brick(queue, inflight, steps, foot, cull)
                    if n is None:
                        break  # every brick in reach waits for one in front of it
                    brick = queue.pop(n)
                    rect = foot[brick.index][0]
                    if rect[0] >= rect[1] or rect[2] >= rect[3] or (
                            cull and occluded(comp.depth, comp.hit, *foot[brick.index])):
                        culled.append(brick.index)  # off screen or hidden: nothing to see
                        done += 1
                        continue
                    task = BrickTask(self._token, brick.index, brick.read, self.model,
                                     self._model_kwargs, self.device, self._isovalue, cam,
                                     (w, h), tuple(user), self.cache_bytes, rect,
                                     self.grid.placement(brick, vol.origin))
                    fut = client.submit(render_brick, shared, task, pure=False)
                    self._pending.append(fut)
                    inflight[fut.key] = brick
                    pending.add(fut)
                if not self._pending:
                    break
                fut = next(pending)
                self._pending.remove(fut)
                inflight.pop(fut.key, None)
                frag = fut.result()
                if frag.stats.get("bounds") is not None:
                    self.brick_bounds[frag.index] = frag.stats["bounds"]
                t = time.perf_counter()
                if composite == "nearest":
                    comp.add_nearest(frag)
                else:
                    fragments.append(frag)
                t_comp += time.perf_counter() - t
                done += 1
                self._record(frag)
                if queue or self._pending:
                    yield "bricks", done, total, volume_frame.frame_to_world(vol, Frame(
                        comp.hit, comp.position, comp.normal, comp.depth, comp.color))
        finally:
            # a closed generator (a newer camera) cancels what is still out
            self.cancel()
        if composite == "back-to-front":
            t = time.perf_counter()
            rank = {b.index: n for n, b in enumerate(order)}
            for frag in sorted(fragments, key=lambda f: -rank[f.index]):
                comp.paint(frag)
            t_comp += time.perf_counter() - t
        self.stats.update(bricks=len(self.grid), bricks_empty=len(empty),
                          bricks_culled=len(culled), bricks_rendered=total - len(culled),
                          composite_s=t_comp, render_s=time.perf_counter() - t_start,
                          workers=nworkers, classified="visible")
        yield "exact", total, total, volume_frame.frame_to_world(vol, comp.frame())

    @staticmethod
    def _next_brick(queue, inflight, steps, foot, cull, window: int = 64):
        """Index in ``queue`` of the next brick to send: the first one (within ``window``)
        that no brick still out lies in front of with an overlapping footprint, so that its
        occlusion test sees every brick that could hide it; None when all wait. Bricks of
        equal slab steps never hide one another (:meth:`BrickGrid.visibility_order`)."""
        if not cull or not inflight:
            return 0
        out = list(inflight.values())
        for n, brick in enumerate(queue[:window]):
            rect = foot[brick.index][0]
            if not any(steps[a.index] < steps[brick.index]
                       and _overlap(foot[a.index][0], rect) for a in out):
                return n
        return None

    def _record(self, frag: Fragment) -> None:
        """Per-brick timings of the last frame (``stats["brick_times"]``; ``pixels``: of the
        brick's window)."""
        self.stats["brick_times"].append({"index": frag.index, **{k: frag.stats.get(k) for k in (
            "read_s", "build_s", "render_s", "cached", "worker", "pixels")}})

    def _render_preview(self, camera, size, planes) -> Frame:
        """The coarse level, ray cast here (its caster is kept for later frames)."""
        if self._preview is None:
            # trilinear, as the window's previews while the camera moves (thesis §6.3): the
            # cheapest kernel to build and run; the bricks bring the model's own surface
            self._preview = self.preview_caster("trilinear")
        self._preview.set_isovalue(self._isovalue)
        return self._preview.render(camera, size=size, clip_planes=planes)


def _overlap(a, b) -> bool:
    """Whether two pixel rectangles (r0, r1, c0, c1) share a pixel."""
    return a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3]


_masses: dict = {}


def _negative_mass(model: str, device, model_kwargs: dict) -> float:
    """The model's negative weight mass (from a ray caster of a tiny volume, built once)."""
    key = (model, device, tuple(sorted(model_kwargs.items())))
    if key not in _masses:
        rc = RayCaster(np.zeros((4, 4, 4), np.float32), model=model, device=device,
                       **model_kwargs)
        _masses[key] = rc.negative_mass
    return _masses[key]
