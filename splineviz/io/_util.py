"""Small helpers shared by the readers and writers: memory budget, atomic writes, path checks.

Tolerances and limits live here, in one place.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizError
from splineviz.io.errors import (
    CorruptFileError,
    DataFileNotFoundError,
    DataTooLargeError,
    WriteError,
)

#: environment variable overriding the memory budget of one volume, in bytes
MAX_BYTES_ENV = "SPLINEVIZ_MAX_VOLUME_BYTES"
#: fraction of the currently available physical memory one volume may use by default
MEMORY_FRACTION = 0.5
#: hard cap on the number of samples: 32-bit signed indices in VTK and OpenCL kernels
MAX_SAMPLES = 2**31 - 1
#: fewest samples per axis: a trivariate spline needs at least one cell per axis
MIN_SAMPLES_PER_AXIS = 2


def memory_budget() -> int:
    """Bytes one volume may occupy: ``$SPLINEVIZ_MAX_VOLUME_BYTES`` or half the free RAM."""
    env = os.environ.get(MAX_BYTES_ENV)
    if env:
        try:
            return max(int(float(env)), 0)
        except ValueError:
            pass
    try:
        free = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        free = 8 * 2**30
    return int(free * MEMORY_FRACTION)


def check_volume_size(shape, itemsize: int, name: str) -> None:
    """Refuse a volume before allocating it if it cannot fit.

    Parameters
    ----------
    shape : (3,) sequence of int
        Samples per axis as announced by a header.
    itemsize : int
        Bytes per stored sample; the float32 copy of :class:`~splineviz.Volume` is added.
    name : str
        File name for the message.
    """
    dims = [int(n) for n in shape]
    if any(n < 0 for n in dims):
        raise DataTooLargeError(f"{name} announces negative dimensions {tuple(dims)}")
    count = 1
    for n in dims:
        count *= n  # Python ints: no overflow for absurd headers
    if count > MAX_SAMPLES:
        raise DataTooLargeError(
            f"{name} announces {count:,} samples {tuple(dims)}, more than the "
            f"{MAX_SAMPLES:,} this program can index"
        )
    need = count * (int(itemsize) + 4)
    budget = memory_budget()
    if need > budget:
        raise DataTooLargeError(
            f"{name} needs about {need / 2**30:.1f} GiB for {tuple(dims)} samples but only "
            f"{budget / 2**30:.1f} GiB are available (set {MAX_BYTES_ENV} to change the budget)"
        )


def regular_input(path, *, allow_dir: bool = False) -> Path:
    """Return ``path`` as a :class:`Path` if it is an existing regular file (or folder).

    Device files, FIFOs and sockets are refused: reading ``/dev/zero`` or a pipe would hang.
    """
    p = Path(os.fspath(path)).expanduser()
    try:
        st = p.stat()
    except FileNotFoundError:
        raise DataFileNotFoundError(f"file not found: {p}") from None
    except OSError as exc:
        raise DataFileNotFoundError(f"cannot access {p}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        if allow_dir:
            return p
        raise DataFileNotFoundError(f"{p} is a folder, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise DataFileNotFoundError(f"{p} is not a regular file")
    return p


def _umask() -> int:
    """The process umask (reading it means setting it: set it straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_output(path, *, suffix: str | None = None):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    A failed or interrupted write leaves neither a partial file nor a changed target.
    The temporary name keeps the target's suffix because VTK/pyvista writers choose the
    format from it.
    """
    target = Path(os.fspath(path)).expanduser()
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise WriteError(f"cannot write {target}: folder {folder} does not exist")
    sfx = target.suffix if suffix is None else suffix
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=f".part{sfx}", dir=folder)
    except OSError as exc:
        raise WriteError(f"cannot write into {folder}: {exc.strerror or exc}") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if not tmp_path.exists() or tmp_path.stat().st_size == 0:
            raise WriteError(f"writing {target.name} produced no data")
        # mkstemp creates 0600; a saved file gets the mode any new file gets (umask), or
        # keeps the mode of the file it replaces
        try:
            mode = stat.S_IMODE(target.stat().st_mode)
        except OSError:
            mode = 0o666 & ~_umask()
        os.chmod(tmp_path, mode)
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


def as_float_triplet(value, name: str) -> tuple[float, float, float]:
    """A finite 3-tuple of floats from a scalar or a sequence of three."""
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), 3)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {tuple(arr.tolist())}")
    return tuple(float(v) for v in arr)


@contextlib.contextmanager
def reader_errors(name: str, fmt: str):
    """Safety net around a reader: anything a library raises on damaged input that the
    reader did not translate itself becomes a CorruptFileError (MemoryError a
    DataTooLargeError), so a bad file can never surface as a traceback. Found necessary by
    the mutation fuzzer: e.g. ``np.load`` raises ``tokenize.TokenError`` on a damaged header.
    """
    try:
        yield
    except SplinevizError:
        raise
    except MemoryError:
        raise DataTooLargeError(f"{name} needs more memory than is available") from None
    except RecursionError:
        raise CorruptFileError(f"{name} is nested too deeply to be a {fmt} file") from None
    except Exception as exc:  # noqa: BLE001 - the whole point: third-party failure modes
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CorruptFileError(f"{name} cannot be read as {fmt}: {detail}") from None
