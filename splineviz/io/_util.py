"""Small helpers shared by the readers and writers: memory budget, atomic writes, path checks.

Tolerances and limits live here, in one place.
"""

from __future__ import annotations

import contextlib
import contextvars
import glob
import os
import re
import stat
import tempfile
import warnings
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.core.volume import NATIVE_TYPES
from splineviz.io.errors import (
    CorruptFileError,
    DataFileNotFoundError,
    DataTooLargeError,
    OutsideFolderError,
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


def held_bytes(shape, itemsize) -> int:
    """Bytes a volume read in one piece holds at its peak: the samples as stored and the
    :class:`~splineviz.Volume` made of them, which keeps the file's type where it can
    (:data:`~splineviz.core.volume.NATIVE_TYPES`) and holds float32 otherwise.

    Parameters
    ----------
    shape : sequence of int
        Samples per axis.
    itemsize : int or numpy dtype
        The stored sample type, or its size in bytes: every 1- and 2-byte type but float16
        is kept as it is, and every wider type becomes (or is) 4-byte float32.

    Returns
    -------
    int
    """
    count = 1
    for n in shape:
        count *= int(n)  # Python ints: no overflow for absurd headers
    if isinstance(itemsize, (int, np.integer)):
        stored = int(itemsize)
        held = stored if stored <= 2 else 4
    else:
        dtype = np.dtype(itemsize)
        stored = dtype.itemsize
        held = stored if dtype.newbyteorder("=") in NATIVE_TYPES or dtype.kind == "b" else 4
    return count * (stored + held)


def check_volume_size(shape, itemsize, name: str) -> None:
    """Refuse a volume before allocating it if it cannot fit.

    Parameters
    ----------
    shape : (3,) sequence of int
        Samples per axis as announced by a header.
    itemsize : int or numpy dtype
        The stored sample type, or its size in bytes; the :class:`~splineviz.Volume` made of
        the samples is counted in the type it keeps (:func:`held_bytes`).
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
    need = held_bytes(dims, itemsize)
    budget = memory_budget()
    if need > budget:
        raise DataTooLargeError(
            f"{name} needs about {need / 2**30:.1f} GiB for {tuple(dims)} samples but only "
            f"{budget / 2**30:.1f} GiB are available (set {MAX_BYTES_ENV} to change the budget)"
        )


#: a printf-style number in a file name (``img_%03d.png``, ``slice%d.tif``)
PRINTF_NUMBER = re.compile(r"%(0?)(\d*)d")


def has_pattern(path) -> bool:
    """Whether ``path`` names files by a pattern rather than being an existing file: a glob
    pattern (``*``, ``?`` or ``[...]`` in its name) or a printf-style number
    (``img_%03d.png``)."""
    p = Path(os.fspath(path)).expanduser()
    return (glob.has_magic(p.name) or PRINTF_NUMBER.search(p.name) is not None) and \
        not p.exists()


def regular_input(path, *, allow_dir: bool = False, allow_pattern: bool = False) -> Path:
    """Return ``path`` as a :class:`Path` if it is an existing regular file (or folder, or
    a pattern of files: :func:`has_pattern`).

    Device files, FIFOs and sockets are refused: reading ``/dev/zero`` or a pipe would hang.
    """
    p = Path(os.fspath(path)).expanduser()
    if allow_pattern and has_pattern(p):
        return p
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


def open_regular(path, mode: str = "rb"):
    """Open ``path`` for reading only if it is a regular file, without ever blocking.

    The file is opened with ``O_NONBLOCK`` and checked with ``fstat`` on the open descriptor,
    so a FIFO, a device or a file swapped for one after an earlier ``stat`` is refused
    instead of hanging the reader (opening a FIFO for reading blocks until a writer comes).
    """
    p = Path(os.fspath(path))
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise DataFileNotFoundError(f"file not found: {p}") from None
    except OSError as exc:
        raise DataFileNotFoundError(f"cannot open {p}: {exc.strerror or exc}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise DataFileNotFoundError(f"{p} is not a regular file")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)  # a regular file: ordinary reads from here on
        return os.fdopen(fd, mode)
    except BaseException:
        os.close(fd)
        raise


# ---------------------------------------------------------------------------- confinement
#: whether files named by headers or sessions may lie outside the naming file's folder;
#: set for the duration of one read by :func:`outside_allowed` (a context variable, so a
#: reader in another thread or job is not affected)
_OUTSIDE_ALLOWED: contextvars.ContextVar[bool] = contextvars.ContextVar(
    "splineviz_outside_allowed", default=False)


@contextlib.contextmanager
def outside_allowed(allow: bool = True):
    """Let :func:`confined` accept files outside the naming file's folder inside the block."""
    token = _OUTSIDE_ALLOWED.set(bool(allow))
    try:
        yield
    finally:
        _OUTSIDE_ALLOWED.reset(token)


def confined(name, referrer, *, what: str = "data file", error=OutsideFolderError,
             folder=None) -> Path:
    """The file ``name`` that ``referrer`` (a header or session) refers to, resolved against
    the referrer's folder, refused if it resolves outside that folder.

    Parameters
    ----------
    name : str or path-like
        The reference as written in the header (relative, absolute, ``..``, a symbolic link).
    referrer : path-like
        The header or session file that names it.
    what : str
        What the file is, for the message.
    error : type
        The :class:`OutsideFolderError` subclass to raise.
    folder : path-like, optional
        The folder to stay in when it is not the referrer's (a DICOM series folder).

    Returns
    -------
    Path
        ``referrer.parent / name`` made absolute (symbolic links kept in the name, so
        messages show what the user wrote); its real path is under the real folder, or
        :func:`outside_allowed` is in force.

    Raises
    ------
    OutsideFolderError
        With ``path`` and ``folder`` set, so a GUI can ask the user and retry.
    """
    ref = Path(os.fspath(referrer))
    raw = os.fspath(name)
    if "\x00" in raw:
        raise CorruptFileError(f"{ref.name} names a {what} containing a NUL character")
    base = ref.parent if folder is None else Path(os.fspath(folder))
    target = Path(os.path.abspath(base / Path(raw).expanduser()))
    if _OUTSIDE_ALLOWED.get():
        return target
    folder = Path(os.path.realpath(base))
    real = Path(os.path.realpath(target))
    if real != folder and folder not in real.parents:
        raise error(
            f"{ref.name} names the {what} {raw}, which resolves to {real} outside {folder}; "
            "allow it explicitly to read it (allow_outside=True, --allow-outside-data)",
            path=real, folder=folder, referrer=ref)
    return target


# ---------------------------------------------------------------------------- writing
def _umask() -> int:
    """The process umask (reading it means setting it: set it straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _write_failed(target: Path, exc: OSError) -> WriteError:
    """One sentence for an OS failure while writing ``target`` (ENOSPC, EFBIG, EACCES...)."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    return WriteError(f"cannot write {target}: {reason}; the previous file, if any, is "
                      "unchanged")


def _fsync_folder(folder: Path) -> None:
    """Make a rename durable (POSIX: the directory entry lives in the folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return  # e.g. Windows: folders cannot be opened; the rename is already atomic there
    try:
        with contextlib.suppress(OSError):
            os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_output(path, *, suffix: str | None = None, expected_size: int | None = None,
                  verify=None):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only when complete.

    The one writer every output goes through (volumes, meshes, screenshots, sessions,
    reports). After the caller has written the temporary file it is flushed to disk
    (``fsync``), its size is checked (not empty; exactly ``expected_size`` when given) and
    ``verify(tmp)`` may read it back; only then is it renamed over the target. A failed,
    short or interrupted write therefore leaves the previous file byte for byte and no
    temporary file. The saved file gets the mode of the file it replaces, or the mode the
    umask gives any new file. The temporary name keeps the target's suffix because
    VTK/pyvista writers choose the format from it.

    Parameters
    ----------
    path : path-like
        The file to (re)place.
    suffix : str, optional
        Suffix of the temporary file (default: the target's).
    expected_size : int, optional
        Bytes the complete file has; a different size is a failed write.
    verify : callable, optional
        ``verify(tmp_path)`` raises :class:`WriteError` when the written file is incomplete
        (used for writers in C libraries that do not report short writes).

    Raises
    ------
    WriteError
        One sentence; OS errors (no space, file too large, permission) are turned into it.
    """
    target = Path(os.fspath(path)).expanduser()
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise WriteError(f"cannot write {target}: folder {folder} does not exist")
    try:
        st = target.stat()
    except OSError:
        st = None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise WriteError(f"cannot write {target}: it is a folder")
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise WriteError(f"cannot write {target}: it exists and is not a regular file")
    sfx = target.suffix if suffix is None else suffix
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=f".part{sfx}", dir=folder)
    except OSError as exc:
        raise WriteError(f"cannot write into {folder}: {exc.strerror or exc}") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
        except OSError as exc:
            if isinstance(exc, SplinevizError):
                raise
            raise _write_failed(target, exc) from None
        try:
            with open(tmp_path, "rb+") as fh:
                os.fsync(fh.fileno())  # ENOSPC/EIO of delayed allocation show up here
                size = os.fstat(fh.fileno()).st_size
        except OSError as exc:
            raise _write_failed(target, exc) from None
        if size == 0:
            raise WriteError(f"writing {target.name} produced no data")
        if expected_size is not None and size != expected_size:
            raise WriteError(f"writing {target.name} stopped after {size:,} of "
                             f"{expected_size:,} bytes; the previous file, if any, is unchanged")
        if verify is not None:
            verify(tmp_path)
        # mkstemp creates 0600; a saved file gets the mode any new file gets (umask), or
        # keeps the mode of the file it replaces
        mode = stat.S_IMODE(st.st_mode) if st is not None else 0o666 & ~_umask()
        try:
            os.chmod(tmp_path, mode)
            os.replace(tmp_path, target)
        except OSError as exc:
            raise _write_failed(target, exc) from None
        _fsync_folder(folder)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through :func:`atomic_output` (size checked); returns the
    path."""
    target = Path(os.fspath(path)).expanduser()
    with atomic_output(target, expected_size=len(data)) as tmp:
        with open(tmp, "wb") as fh:
            view = memoryview(data)
            while view:
                n = fh.write(view)  # short writes are retried; errors raise
                view = view[n:]
    return target


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

    Warnings of the libraries (NumPy's overflow in a damaged header's arithmetic, nibabel's
    and MetaIO's notes) are not passed on: the reader turns what matters into an error, and
    splineviz's own documented acceptances are warned outside the readers.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            warnings.simplefilter("always", SplinevizWarning)  # a plugin reader's own
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
