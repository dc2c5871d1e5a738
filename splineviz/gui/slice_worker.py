"""The slice views' worker: slices of a spline computed in one thread, off the GUI thread.

A slice (:mod:`splineviz.core.slice_sampling`) needs its volume's spline, which takes up to
a second to build for the smooth models, then the spline sampled on the slice and the
exact contours of the isosurfaces (0.1-0.3 s on a 256^2 slice). :class:`SliceWorker`
builds and keeps the splines, computes the newest request of each view (a request not
started yet is replaced by a newer one of its view) and hands the results to the GUI thread
through a queued Qt signal; a result that a newer request of its view has made outdated is
dropped.

A chunked volume (OME-Zarr, bricked stores) is never read whole: a slice reads the slab of
samples around its plane (:func:`read_slab`: :data:`SLAB_MARGIN` samples on each side, the
reach of the models' stencils, so the slab's spline is the whole volume's on the plane) from
the finest level whose slab stays under :data:`MAX_SLAB_SAMPLES`, in this thread, and builds
the spline of that slab.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
from PySide6.QtCore import QObject, Signal

from splineviz.core import slice_sampling

#: splines kept built by the worker (a model switch back is immediate)
SPLINE_CACHE = 4
#: image samples per data grid step along each in-plane axis
OVERSAMPLE = 2
#: samples of a chunked volume read on each side of a slice. The built-in models' values on
#: the plane depend on samples up to 2 away (slab and whole volume agree to 1e-15 with 2,
#: tests/gui/test_chunked_slices.py); 4 leaves room for a plugin's wider stencils
SLAB_MARGIN = 4
#: most samples of one slab read from a chunked volume (64 MiB of float32); a bigger plane is
#: read from a coarser level of the store
MAX_SLAB_SAMPLES = 2**24
#: slabs kept read (three views, a step back and forth each)
SLAB_CACHE = 6


@dataclass(frozen=True, eq=False)
class SliceRequest:
    """What one slice view needs computed.

    Attributes
    ----------
    volume : Volume or ChunkedVolume, the samples (the volume's active data)
    model : str, the spline model of the image
    options : tuple of (name, value), the model's keyword arguments, sorted
    axis, position : the slice
    isos : tuple of (model, options, isovalue, colour) of the isosurfaces to contour
    """

    volume: object
    model: str
    options: tuple
    axis: int
    position: float
    isos: tuple = field(default=())


@dataclass(frozen=True, eq=False)
class SliceResult:
    """A computed slice: the grid, its ``(nv, nu)`` values, the contours and their colours."""

    request: SliceRequest
    grid: slice_sampling.SliceGrid
    values: np.ndarray
    curves: list
    colors: list


@dataclass(frozen=True, eq=False)
class Slab:
    """Samples of a chunked volume around one slice.

    Attributes
    ----------
    source : ChunkedVolume, the volume read
    volume : Volume, the samples read (world geometry of their level)
    axis : int, the axis normal to the slice
    inner : (lo, hi), the world range along ``axis`` where the slab's spline is the whole
        volume's (the slab less its margins, except at the volume's own faces)
    """

    source: object
    volume: object
    axis: int
    inner: tuple[float, float]


def read_slab(volume, axis: int, position: float, margin: int = SLAB_MARGIN,
              max_samples: int = MAX_SLAB_SAMPLES) -> Slab:
    """Read the samples of ``volume`` (a ChunkedVolume) within ``margin`` samples of the
    plane ``x[axis] = position``, across the whole plane, from its finest level whose slab
    has at most ``max_samples`` samples (the coarsest otherwise).

    Returns
    -------
    Slab
    """
    levels = volume.all_levels()
    chosen = len(levels) - 1
    for n, level in enumerate(levels):
        plane = np.prod([level.shape[a] for a in range(3) if a != axis], dtype=np.int64)
        if plane * min(2 * margin + 2, level.shape[axis]) <= max_samples:
            chosen = n
            break
    level = levels[chosen]
    size, origin, step = level.shape[axis], level.origin[axis], level.spacing[axis]
    index = min(max((position - origin) / step, 0.0), size - 1.0)
    i0 = max(int(np.floor(index)) - margin, 0)
    # an even first sample: the truncated-octahedral partition (to-quadratic) alternates
    # with the parity of the sample index, so a slab must keep the volume's
    i0 -= i0 % 2
    i1 = min(int(np.ceil(index)) + margin + 1, size)
    box = [(0, n) for n in level.shape]
    box[axis] = (i0, i1)
    if chosen == 0:
        samples = volume.read(box)
    else:
        from splineviz.core.volume import Volume

        sl = tuple(slice(a, b) for a, b in box)
        data = np.asarray(level.data[sl].compute(scheduler="threads"))
        shifted = list(level.origin)
        shifted[axis] = origin + i0 * step
        samples = Volume(data, spacing=level.spacing, origin=tuple(shifted), unit=volume.unit)
    # a margin cut short by the volume's face is that face: the whole volume ends there too
    lo = origin + (i0 + (margin if i0 > 0 else 0)) * step
    hi = origin + (i1 - 1 - (margin if i1 < size else 0)) * step
    return Slab(volume, samples, axis, (lo, hi))


class SliceWorker(QObject):
    """Computes slices in one thread, newest request per view first (see module docstring).

    Signals
    -------
    computed(str, object)
        A view's :class:`SliceResult` (in the GUI thread).
    failed(str)
        One sentence of an error.
    """

    computed = Signal(str, object)
    failed = Signal(str)
    _finished = Signal(str, object, object)

    def __init__(self, parent=None):
        super().__init__(parent)
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="slices")
        self._pending: dict[str, SliceRequest] = {}
        self._running = False
        self._closed = False
        self._splines: dict[tuple, object] = {}
        #: slabs read from chunked volumes, by (id(volume), axis, inner range), newest last
        self._slabs: dict[tuple, Slab] = {}
        self._lock = threading.Lock()  # the spline cache, between the worker and the probe
        self._finished.connect(self._done)

    def request(self, name: str, req: SliceRequest) -> None:
        """Compute ``req`` for view ``name`` (replaces a request of it not started yet)."""
        if self._closed:
            return
        self._pending[name] = req
        self._kick()

    @property
    def busy(self) -> bool:
        return self._running or bool(self._pending)

    def spline(self, volume, model: str, options: tuple, point=None):
        """The spline built for these samples and model, or None if not built yet; for a
        chunked volume, the spline of a slab read for a slice through ``point`` (world)."""
        with self._lock:
            spline = self._splines.get((id(volume), model, options))
            if spline is not None or point is None:
                return spline
            for slab in reversed(self._slabs.values()):
                lo, hi = slab.inner
                if slab.source is volume and lo <= point[slab.axis] <= hi:
                    found = self._splines.get((id(slab.volume), model, options))
                    if found is not None:
                        return found
            return None

    def _samples(self, volume, axis: int, position: float):
        """What a slice's spline is built on: the volume, or for a chunked one the slab
        around the slice (read here, in the worker's thread; kept for the next request)."""
        from splineviz.core.chunked import ChunkedVolume

        if not isinstance(volume, ChunkedVolume):
            return volume
        with self._lock:
            for slab in self._slabs.values():
                lo, hi = slab.inner
                if slab.source is volume and slab.axis == axis and lo <= position <= hi:
                    return slab.volume
        slab = read_slab(volume, axis, position)
        with self._lock:
            self._slabs[(id(volume), axis, slab.inner)] = slab
            while len(self._slabs) > SLAB_CACHE:
                self._slabs.pop(next(iter(self._slabs)))
        return slab.volume

    def _kick(self) -> None:
        if self._running or not self._pending or self._closed:
            return
        name = next(iter(self._pending))
        req = self._pending.pop(name)
        self._running = True
        future = self._pool.submit(self._compute, req)
        future.add_done_callback(lambda f, n=name, r=req: self._finished.emit(n, r, f))

    def _build(self, volume, model: str, options: tuple):
        from splineviz.core.splines import build_spline

        key = (id(volume), model, options)
        with self._lock:
            spline = self._splines.get(key)
        if spline is None:
            spline = build_spline(volume, model, **dict(options))
            with self._lock:
                self._splines[key] = spline
                # a volume kept alive by the key's spline; the oldest go first
                while len(self._splines) > SPLINE_CACHE:
                    self._splines.pop(next(iter(self._splines)))
        return spline

    def _compute(self, req: SliceRequest) -> SliceResult:
        samples = self._samples(req.volume, req.axis, req.position)
        spline = self._build(samples, req.model, req.options)
        grid = slice_sampling.slice_grid(spline.bounds, samples.spacing, req.axis,
                                         req.position, OVERSAMPLE)
        values = slice_sampling.sample_slice(spline, grid)
        curves, colors = [], []
        for model, options, iso, color in req.isos:
            s = self._build(samples, model, options)
            for curve in slice_sampling.slice_contours(s, iso, req.axis, grid.position):
                curves.append(curve)
                colors.append(color)
        return SliceResult(req, grid, values, curves, colors)

    def _done(self, name: str, req: SliceRequest, future) -> None:
        self._running = False
        if self._closed:
            return
        exc = future.exception()
        if exc is not None:
            from splineviz.gui.jobs import error_message

            self.failed.emit(error_message(exc))
        elif name not in self._pending:  # an outdated result is not shown
            self.computed.emit(name, future.result())
        self._kick()

    def wait(self, timeout_s: float = 60.0) -> bool:
        """Test helper: run the event loop until no slice is pending."""
        import time

        from PySide6.QtWidgets import QApplication

        end = time.perf_counter() + timeout_s
        while self.busy and time.perf_counter() < end:
            QApplication.processEvents()
            time.sleep(0.005)
        QApplication.processEvents()
        return not self.busy

    def close(self) -> None:
        self._closed = True
        self._pending.clear()
        self._pool.shutdown(wait=False, cancel_futures=True)
