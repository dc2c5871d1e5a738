"""Time-varying volumes: a sequence of 3-D steps read lazily, cached and read ahead.

A :class:`TimeSeries` is what a time-varying volume node shows one step of
(:mod:`splineviz.model.nodes`): ``len(series)`` steps at ``series.times`` (in
``series.unit``), of which ``series.step(i)`` reads one when it is first asked for and keeps
it in a least-recently-used cache bounded in bytes (:data:`DEFAULT_CACHE_FRACTION` of the
memory available when it is made, at most :data:`MAX_CACHE_BYTES`). :meth:`TimeSeries.
read_ahead` reads the next steps on a background thread, so that a player asking for step
``i + 1`` finds it read.

:func:`open_time_series` makes one from a 4-D file (NIfTI, MGH, MINC, NRRD, .npy, ...: the
file's own time axis, :func:`~splineviz.io.sequence.read_volume_sequence`), a folder of 3-D
files, or a pattern (``run_####.vti``, ``run_*.npy``); :meth:`TimeSeries.from_array` from a
NumPy or dask array with a leading time axis.
"""

from __future__ import annotations

import glob
import mmap
import os
import re
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import numpy as np

from splineviz.core.volume import Volume
from splineviz.io.errors import InvalidDataError

#: share of the available memory the steps of one series may keep cached
DEFAULT_CACHE_FRACTION = 0.25
#: most bytes of steps one series keeps cached, however much memory is free
MAX_CACHE_BYTES = 4 << 30
#: most steps one series keeps, whatever their size (memory-mapped steps hold no memory of
#: their own, but each keeps its view of the file)
MAX_CACHED_STEPS = 64
#: seconds per unit of the time units a ``--time 2.5s`` may name
TIME_UNITS = {"ns": 1e-9, "us": 1e-6, "µs": 1e-6, "ms": 1e-3, "s": 1.0, "sec": 1.0,
              "min": 60.0, "h": 3600.0}


class TimeSeriesError(InvalidDataError):
    """A step or time a series does not have, or files that do not form a series."""


def default_cache_bytes() -> int:
    """:data:`DEFAULT_CACHE_FRACTION` of the memory available now, at most
    :data:`MAX_CACHE_BYTES`."""
    import psutil

    return int(min(MAX_CACHE_BYTES, DEFAULT_CACHE_FRACTION * psutil.virtual_memory().available))


def held_bytes(volume) -> int:
    """Bytes of memory a step holds: its samples, unless they are memory-mapped from the
    file (the page cache holds them) or a chunked volume's (read brick by brick)."""
    data = getattr(volume, "data", None)
    if not isinstance(data, np.ndarray):
        return 0
    base = data
    while base is not None:
        if isinstance(base, np.memmap | mmap.mmap):
            return 0
        base = getattr(base, "base", None)
    return int(data.nbytes)


class TimeSeries(Sequence):
    """The steps of a time-varying volume, each read when first asked for.

    Parameters
    ----------
    name : str
        What the user knows the series by (the file or pattern).
    count : int
        Number of steps.
    read : callable
        ``read(i) -> Volume``: step ``i`` (all steps have one shape and geometry). Called
        on a background thread by :meth:`read_ahead`, so it must not touch shared state.
    times : sequence of float, optional
        The time of each step (increasing), in ``unit``; default the step indices.
    unit : str
        Unit of ``times`` (``"s"``, ``"ms"``, ...; ``""`` when the data do not say).
    cache_bytes : int, optional
        Most bytes of steps kept (default :func:`default_cache_bytes`); at least the step
        asked for last is always kept.
    axis : str
        What the steps run along, as the file names it (``"time"``, ``"echo"``,
        ``"channel"``, ``"frame"``).

    Examples
    --------
    >>> series = TimeSeries.from_array(np.zeros((4, 8, 8, 8), np.uint8), times=[0, 1, 2, 3])
    >>> len(series), series.step(2).shape, series.index_of(2.0)
    (4, (8, 8, 8), 2)
    """

    def __init__(self, name: str, count: int, read: Callable[[int], Volume], *,
                 times: Sequence[float] | None = None, unit: str = "",
                 cache_bytes: int | None = None, axis: str = "time"):
        if count < 1:
            raise TimeSeriesError(f"{name} holds no time step")
        times = tuple(float(t) for t in (range(count) if times is None else times))
        if len(times) != count:
            raise TimeSeriesError(f"{name} has {count} steps but {len(times)} times")
        if count > 1 and not np.all(np.diff(times) > 0):
            raise TimeSeriesError(f"the times of {name} do not increase step by step")
        self.name = name
        self.times = times
        self.unit = unit
        self.axis = axis
        self.cache_bytes = default_cache_bytes() if cache_bytes is None else int(cache_bytes)
        self._count = count
        self._read = read
        self._lock = threading.Lock()
        self._cache: OrderedDict[int, Volume] = OrderedDict()
        self._pending: dict[int, Future] = {}
        self._pool: ThreadPoolExecutor | None = None
        #: reads done (a cache hit is none): what tests and the benchmark count
        self.reads = 0
        #: ``prepare(volume)``, run on the reading thread after each read: what the views
        #: of a step need computed (its range, its histogram) is then ready when it shows
        self.prepare: Callable[[Volume], None] | None = None

    # -- construction ----------------------------------------------------------------------

    @classmethod
    def from_array(cls, array, *, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0),
                   times=None, unit: str = "", name: str = "array",
                   cache_bytes: int | None = None) -> TimeSeries:
        """A series of the steps ``array[i]`` of a ``(nt, nx, ny, nz)`` NumPy, dask or other
        array-like (anything with ``shape`` and indexing: a dask array computes one step
        when it is read)."""
        if len(getattr(array, "shape", ())) != 4:
            raise TimeSeriesError(f"{name}: a time series array must be 4-D (t, x, y, z), "
                                  f"got shape {tuple(getattr(array, 'shape', ()))}")
        return cls(name, int(array.shape[0]), _ArraySteps(array, spacing, origin), times=times,
                   unit=unit, cache_bytes=cache_bytes)

    # -- pickling (a session's series is opened in a job process) --------------------------

    def __getstate__(self) -> dict:
        # the steps read so far travel with it; the lock, the reads under way and the
        # read-ahead thread are the process's own
        with self._lock:
            return {k: v for k, v in self.__dict__.items()
                    if k not in ("_lock", "_pending", "_pool", "prepare")}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _lock=threading.Lock(), _pending={}, _pool=None,
                             prepare=None)

    # -- access ----------------------------------------------------------------------------

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self.step(k) for k in range(*i.indices(len(self)))]
        return self.step(i)

    def check_index(self, i) -> int:
        """``i`` as a step index (negative counts from the end), or a one-sentence error."""
        k = int(i)
        k = k + self._count if k < 0 else k
        if not 0 <= k < self._count:
            raise TimeSeriesError(f"{self.name} has {self._count} step(s) (0 to "
                                  f"{self._count - 1}); step {i} is not one")
        return k

    def step(self, i: int) -> Volume:
        """The volume of step ``i``: from the cache, from a read ahead under way, or read
        now (blocks; the GUI calls it from a job thread)."""
        return self._future(self.check_index(i)).result()

    def cached(self, i: int) -> bool:
        """Whether step ``i`` is read and kept (:meth:`step` returns at once)."""
        with self._lock:
            return self.check_index(i) in self._cache

    def read_ahead(self, i: int, count: int = 2, direction: int = 1, loop: bool = False) -> None:
        """Start reading the ``count`` steps after ``i`` (before it when ``direction`` is
        -1; wrapping round when ``loop``) on the background thread, as far as the cache
        holds them beside step ``i``."""
        i = self.check_index(i)
        with self._lock:
            nbytes = max((held_bytes(v) for v in self._cache.values()), default=0)
        room = count if not nbytes else min(count, self.cache_bytes // nbytes - 1)
        for n in range(1, max(room, 0) + 1):
            k = i + direction * n
            if loop:
                k %= self._count
            if 0 <= k < self._count and k != i:
                self._future(k)

    def close(self) -> None:
        """Stop the read-ahead thread and drop the cached steps."""
        with self._lock:
            pool, self._pool = self._pool, None
            self._cache.clear()
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)

    # -- time ------------------------------------------------------------------------------

    def index_of(self, time: float, unit: str | None = None) -> int:
        """The step at ``time`` (in ``unit``, default the series' own), or a one-sentence
        error when no step is at that time."""
        t = float(time)
        if unit is not None and unit != self.unit:
            if unit not in TIME_UNITS or self.unit not in TIME_UNITS:
                have = f"in {self.unit}" if self.unit else "without a unit"
                raise TimeSeriesError(f"{self.name} gives its times {have}; a time in {unit} "
                                      "cannot be converted to them")
            t = t * TIME_UNITS[unit] / TIME_UNITS[self.unit]
        times = np.asarray(self.times)
        span = float(times[-1] - times[0]) or 1.0
        k = int(np.argmin(np.abs(times - t)))
        if abs(times[k] - t) > 1e-9 * span + 1e-12 * abs(t):
            raise TimeSeriesError(f"{self.name} has no step at {format_time(t, self.unit)}; "
                                  f"its {self._count} steps run from "
                                  f"{format_time(times[0], self.unit)} to "
                                  f"{format_time(times[-1], self.unit)}")
        return k

    def index_at_or_before(self, time: float) -> int:
        """The last step whose time is at or before ``time`` (the first step before the
        series starts): the step a scene shows at ``time``."""
        return max(0, int(np.searchsorted(np.asarray(self.times), time, side="right")) - 1)

    def parse_step(self, text: str) -> int:
        """The step a user names: an index (``"3"``, ``"-1"``) or a time with a unit
        suffix (``"2.5s"``, ``"250ms"``)."""
        m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-zµ]*)\s*",
                         str(text))
        if m is None:
            raise TimeSeriesError(f"--time takes a step index or a time with a unit such as "
                                  f"2.5s, not {text!r}")
        number, unit = m.groups()
        if not unit:
            if not re.fullmatch(r"[-+]?\d+", number):
                raise TimeSeriesError(f"a step index is a whole number; give a time with its "
                                      f"unit (e.g. {number}{self.unit or 's'}), not {text!r}")
            return self.check_index(int(number))
        if unit not in TIME_UNITS and unit != self.unit:
            raise TimeSeriesError(f"unknown time unit {unit!r} in {text!r}; use one of "
                                  f"{', '.join(TIME_UNITS)}")
        return self.index_of(float(number), unit)

    # -- internals -------------------------------------------------------------------------

    def _future(self, i: int) -> Future:
        with self._lock:
            if i in self._cache:
                self._cache.move_to_end(i)
                done = Future()
                done.set_result(self._cache[i])
                return done
            fut = self._pending.get(i)
            if fut is None:
                if self._pool is None:
                    # one reader: steps come off one file or disk in order
                    self._pool = ThreadPoolExecutor(1, thread_name_prefix="time-series")
                fut = self._pending[i] = self._pool.submit(self._load, i)
            return fut

    def _load(self, i: int) -> Volume:
        try:
            vol = self._read(i)
            if self.prepare is not None:
                self.prepare(vol)
        finally:
            with self._lock:
                self._pending.pop(i, None)
        with self._lock:
            self.reads += 1
            self._cache[i] = vol
            self._cache.move_to_end(i)
            total = sum(held_bytes(v) for v in self._cache.values())
            while len(self._cache) > 1 and (total > self.cache_bytes
                                            or len(self._cache) > MAX_CACHED_STEPS):
                _, old = self._cache.popitem(last=False)
                total -= held_bytes(old)
        return vol

    def __repr__(self) -> str:
        return (f"<TimeSeries {self.name}: {len(self)} steps from "
                f"{format_time(self.times[0], self.unit)} to "
                f"{format_time(self.times[-1], self.unit)}>")


class _ArraySteps:
    """Reads step ``i`` of a ``(t, x, y, z)`` array (a dask array computes that step)."""

    def __init__(self, array, spacing, origin):
        self.array = array
        self.spacing = tuple(map(float, spacing))
        self.origin = tuple(map(float, origin))

    def __call__(self, i: int) -> Volume:
        step = self.array[i]
        step = step.compute() if hasattr(step, "compute") else step
        return Volume(np.ascontiguousarray(step), spacing=self.spacing, origin=self.origin)


class _SequenceSteps:
    """Reads frame ``i`` of a 4-D file (:func:`~splineviz.io.sequence.read_volume_sequence`,
    opened again after pickling, on the first read)."""

    def __init__(self, path, options: dict, sequence=None):
        self.path = os.fspath(path)
        self.options = options
        self._sequence = sequence

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_sequence": None}

    def __call__(self, i: int) -> Volume:
        from splineviz.io.sequence import read_volume_sequence

        if self._sequence is None:
            self._sequence = read_volume_sequence(self.path, **self.options)
        return self._sequence[i]


class _FileSteps:
    """Reads the ``i``-th file of a series; every step must have the first one's shape."""

    def __init__(self, name: str, files: list[Path], options: dict):
        self.name = name
        self.files = files
        self.options = options
        self.shape = None

    def __call__(self, i: int) -> Volume:
        from splineviz.io.volumes import read_volume

        if self.shape is None and i != 0:
            self.shape = read_volume(self.files[0], **self.options).shape
        vol = read_volume(self.files[i], **self.options)
        self.shape = self.shape or vol.shape
        if vol.shape != self.shape:
            raise TimeSeriesError(f"{self.files[i].name} holds {vol.shape} samples, but the "
                                  f"first file of {self.name} {self.shape}; a series keeps "
                                  "one shape")
        return vol


class _ZarrSteps:
    """Reads time index ``i`` of an OME-Zarr image as a chunked volume."""

    def __init__(self, path: Path, spacing=None, origin=None):
        self.path = path
        self.spacing = spacing
        self.origin = origin

    def __call__(self, i: int) -> Volume:
        from splineviz.io.chunked import _read_zarr, to_chunked_volume
        from splineviz.io.volumes import validate_volume_data

        vd = _read_zarr(self.path, t=i)
        validate_volume_data(vd, self.path.name)
        return to_chunked_volume(vd, self.path.name, spacing=self.spacing, origin=self.origin)


def format_time(t: float, unit: str = "") -> str:
    """``t`` as the user reads it: ``"2.5 s"``, or ``"3"`` without a unit."""
    return f"{t:g} {unit}" if unit else f"{t:g}"


#: suffixes of the 3-D volume files a folder series is made of (2-D slices and DICOM files
#: in a folder are one volume, read by :func:`~splineviz.io.volumes.read_volume`)
SERIES_SUFFIXES = (".vti", ".nrrd", ".nhdr", ".mha", ".mhd", ".vtk", ".nii", ".nii.gz",
                   ".mgz", ".mgh", ".mnc", ".mrc", ".map", ".npy")


def _suffix(f: Path) -> str:
    name = f.name.lower()
    return ".nii.gz" if name.endswith(".nii.gz") else f.suffix.lower()


def series_files(path) -> list[Path] | None:
    """The files of a series named by ``path``: a folder of 3-D volume files
    (:data:`SERIES_SUFFIXES`; the most common one), a ``#`` pattern (``run_####.vti``: one
    digit per ``#``) or a glob pattern (``run_*.npy``), in natural order; None when
    ``path`` names one file or a folder of slices."""
    p = Path(os.fspath(path)).expanduser()
    if p.is_dir():
        files = [f for f in p.iterdir() if f.is_file() and _suffix(f) in SERIES_SUFFIXES
                 and not f.name.startswith(".")]
        if not files:
            return None
        suffixes = [_suffix(f) for f in files]
        common = max(set(suffixes), key=suffixes.count)
        files = [f for f in files if _suffix(f) == common]
    elif "#" in p.name:
        regex = "".join(r"\d" if c == "#" else re.escape(c) for c in p.name)
        files = [f for f in p.parent.glob("*") if re.fullmatch(regex, f.name)]
    elif glob.has_magic(p.name) and _suffix(p) in SERIES_SUFFIXES:
        files = [Path(f) for f in glob.glob(str(p))]
    else:
        return None
    if not files:
        raise TimeSeriesError(f"no file matches {p.name}")
    return sorted(files, key=lambda f: [int(s) if s.isdigit() else s
                                        for s in re.split(r"(\d+)", f.name)])


def series_info(path, *, channel=None, allow_outside: bool = False) -> dict | None:
    """Steps and times of the time series at ``path`` (what ``splineviz info`` adds), or
    None when ``path`` is a file of one step."""
    series = open_time_series(path, channel=channel, allow_outside=allow_outside,
                              cache_bytes=0)
    if len(series) == 1 and series_files(path) is None:
        return None
    shown = [format_time(t) for t in series.times]
    if len(shown) > 12:  # a long run: its start and end
        shown = [*shown[:5], "...", *shown[-2:]]
    times = ", ".join(shown)
    return {"steps": len(series),
            "times": f"{times} {series.unit}".rstrip() if series.unit else times}


#: OME-NGFF time units -> the short names of :data:`TIME_UNITS`
_NGFF_TIME_UNITS = {"nanosecond": "ns", "microsecond": "us", "millisecond": "ms",
                    "second": "s", "minute": "min", "hour": "h"}


def _ome_zarr_series(path: Path, cache_bytes, spacing=None, origin=None) -> TimeSeries | None:
    """The steps of an OME-Zarr image along its ``t`` axis (each a chunked volume read brick
    by brick), or None when ``path`` is no OME-Zarr image with one."""
    import zarr

    from splineviz.io.chunked import _is_zarr_folder, _ome_levels

    if not (path.is_dir() and _is_zarr_folder(path)):
        return None
    ome = _ome_levels(path)
    if ome is None or "t" not in ome[0]:
        return None
    axes, levels, _ = ome
    k = axes.index("t")
    dataset, scale, shift = levels[0]
    count = int(zarr.open_array(str(path / dataset), mode="r").shape[k])
    attrs = dict(zarr.open_group(str(path), mode="r").attrs)
    multiscales = attrs.get("multiscales") or attrs.get("ome", {}).get("multiscales") or [{}]
    unit = next((a.get("unit", "") for a in multiscales[0].get("axes", [])
                 if isinstance(a, dict) and a.get("name") == "t"), "")
    return TimeSeries(path.name, count, _ZarrSteps(path, spacing, origin),
                      times=[shift[k] + scale[k] * i for i in range(count)],
                      unit=_NGFF_TIME_UNITS.get(unit, unit), cache_bytes=cache_bytes)


def open_time_series(path, *, channel=None, cache_bytes: int | None = None,
                     allow_outside: bool = False, **read_options) -> TimeSeries:
    """A time series from a 4-D file, a folder of 3-D files or a file pattern.

    Parameters
    ----------
    path : path-like
        An OME-Zarr image with a ``t`` axis (its steps chunked volumes, rendered in bricks;
        times from its scale and unit), a file with a fourth (time) axis, read step by step
        (:func:`~splineviz.io.sequence.read_volume_sequence`: its times and their unit come
        from the file); a folder of 3-D volume files of one format, or a pattern
        (``run_####.vti``: ``#`` stands for one digit; ``run_*.npy``), one step per file in
        natural order (``run_2`` before ``run_10``), at times 0, 1, 2, ... (each file is
        read when its step is: one of another shape is refused then); a 3-D file is a
        series of one step.
    channel : int, optional
        The channel of a 5-D or multi-channel file.
    cache_bytes : int, optional
        See :class:`TimeSeries`.
    allow_outside, **read_options
        As for :func:`~splineviz.io.volumes.read_volume` (``format``, ``spacing``,
        ``origin``, ...).

    Raises
    ------
    SplinevizError
        One sentence: the file cannot be read, no file matches, or the files of a series
        differ in shape.
    """
    from splineviz.io.sequence import read_volume_sequence

    files = series_files(path)
    zarr_series = None if files is not None else _ome_zarr_series(
        Path(os.fspath(path)).expanduser(), cache_bytes, read_options.get("spacing"),
        read_options.get("origin"))
    if zarr_series is not None:
        return zarr_series
    if files is None:
        options = {"channel": channel, "allow_outside": allow_outside, **read_options}
        seq = read_volume_sequence(path, **options)
        return TimeSeries(seq.name, len(seq), _SequenceSteps(path, options, seq),
                          times=seq.times, unit=seq.axis.unit if seq.times is not None else "",
                          cache_bytes=cache_bytes, axis=seq.axis.name)
    name = Path(os.fspath(path)).name
    read = _FileSteps(name, files, {"channel": channel, "allow_outside": allow_outside,
                                    **read_options})
    return TimeSeries(name, len(files), read, cache_bytes=cache_bytes)
