"""The slice views' worker: slices of a spline computed in one thread, off the GUI thread.

A slice (:mod:`splineviz.core.slice_sampling`) needs its volume's spline, which takes up to
a second to build for the smooth models, then the spline sampled on the slice and the
exact contours of the isosurfaces (0.1-0.3 s on a 256^2 slice). :class:`SliceWorker`
builds and keeps the splines, computes the newest request of each view (a request not
started yet is replaced by a newer one of its view) and hands the results to the GUI thread
through a queued Qt signal; a result that a newer request of its view has made outdated is
dropped.
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


@dataclass(frozen=True, eq=False)
class SliceRequest:
    """What one slice view needs computed.

    Attributes
    ----------
    volume : Volume, the samples (the volume's active data)
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

    def spline(self, volume, model: str, options: tuple):
        """The spline built for these samples and model, or None if not built yet."""
        with self._lock:
            return self._splines.get((id(volume), model, options))

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
        spline = self._build(req.volume, req.model, req.options)
        grid = slice_sampling.slice_grid(spline.bounds, req.volume.spacing, req.axis,
                                         req.position, OVERSAMPLE)
        values = slice_sampling.sample_slice(spline, grid)
        curves, colors = [], []
        for model, options, iso, color in req.isos:
            s = self._build(req.volume, model, options)
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
