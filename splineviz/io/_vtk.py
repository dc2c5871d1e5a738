"""VTK plumbing for the readers: error capture and image-to-array conversion.

VTK reports problems through its output window instead of raising. :func:`run_vtk` swaps in
a string output window for the duration of one pipeline update and turns any error text into
a :class:`~splineviz.io.errors.CorruptFileError`, so a damaged file never prints noise and
never passes silently.
"""

from __future__ import annotations

import base64
import binascii
import contextlib
import os
import re
import tempfile
import threading

import numpy as np

_LOCK = threading.Lock()  # the output window is process-global


def _vtk():
    from vtkmodules import vtkCommonCore

    return vtkCommonCore


@contextlib.contextmanager
def quiet_vtk_logger():
    """Keep vtkLogger's stderr output off inside the block: off-screen rendering without a
    display logs "bad X server connection" before falling back, which is no news to a user
    who rendered to a file (errors still reach the output window and are reported)."""
    logger = _vtk().vtkLogger
    cutoff = logger.GetCurrentVerbosityCutoff()
    logger.SetStderrVerbosity(logger.VERBOSITY_OFF)
    try:
        yield
    finally:
        logger.SetStderrVerbosity(logger.ConvertToVerbosity(cutoff))


@contextlib.contextmanager
def captured_stderr(sink: list[str]):
    """Collect what C/C++ code writes to file descriptor 2 (``std::cerr``) inside the block
    into ``sink``: MetaIO prints "data not read completely" there, bypassing VTK's output
    window, and a user error must be one line, not a library's report followed by ours."""
    import sys

    with contextlib.suppress(AttributeError, ValueError, OSError):
        sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr at all (a detached GUI): nothing to capture
        yield
        return
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            sink.append(tmp.read(65536).decode("utf-8", "replace"))


@contextlib.contextmanager
def captured_vtk_output():
    """Collect everything VTK would print; yields a list that receives the text on exit.

    Two channels are captured: the output window (``vtkErrorMacro``) and the vtkLogger, through
    which some readers report failures only as warnings (the legacy reader's "Error reading
    binary data!" on a truncated payload). Logger errors and warnings that mention an error
    are turned into ``ERROR`` blocks so :func:`first_vtk_error` finds them.
    """
    core = _vtk()
    logger = core.vtkLogger
    sink: list[str] = []
    with _LOCK, tempfile.TemporaryDirectory(prefix="splineviz-vtklog-") as tmp:
        log_path = os.path.join(tmp, "vtk.log")
        old = core.vtkOutputWindow.GetInstance()
        win = core.vtkStringOutputWindow()
        core.vtkOutputWindow.SetInstance(win)
        cutoff = logger.GetCurrentVerbosityCutoff()
        logger.SetStderrVerbosity(logger.VERBOSITY_OFF)
        logger.LogToFile(log_path, logger.TRUNCATE, logger.VERBOSITY_WARNING)
        cerr: list[str] = []
        try:
            with captured_stderr(cerr):
                yield sink
        finally:
            logger.EndLogToFile(log_path)
            logger.SetStderrVerbosity(logger.ConvertToVerbosity(cutoff))
            core.vtkOutputWindow.SetInstance(old)
            text = win.GetOutput()
            try:
                with open(log_path, encoding="utf-8", errors="replace") as fh:
                    for line in fh:
                        level, _, msg = line.partition("| ")
                        if level.endswith("ERR") or (level.endswith("WARN") and
                                                     "rror" in msg):
                            text += f"\nERROR: vtkLogger\n{msg.strip()}\n"
            except OSError:
                pass
            for line in "".join(cerr).splitlines():
                # MetaIO reports failed reads only here ("M_ReadElementsData: data not read
                # completely"); anything else printed there is noise, not shown either
                if re.search(r"rror|not read|cannot|failed", line):
                    text += f"\nERROR: stderr\n{line.strip()}\n"
            sink.append(text)


def first_vtk_error(text: str, *, generic: str = "the reader failed") -> str | None:
    """The most specific error message in VTK output text, without file/line noise.

    The pipeline's generic "Algorithm ... returned failure" is used only when nothing more
    specific was reported; it is then replaced by ``generic``.
    """
    found = []
    for block in re.split(r"\n(?=(?:ERROR|Generic Warning|Warning))", (text or "").lstrip()):
        if not block.startswith("ERROR"):
            continue
        lines = [ln.strip() for ln in block.splitlines()[1:] if ln.strip()]
        msg = lines[0] if lines else block
        msg = re.sub(r"^\S+ \(0x[0-9a-fA-F]+\):\s*", "", msg)
        msg = re.sub(r"\s*\(0x[0-9a-fA-F]+\)", "", msg).rstrip(".")
        found.append(msg or "unspecified VTK error")
    specific = [m for m in found if "returned failure for request" not in m]
    if specific:
        return specific[0]
    return generic if found else None


def run_vtk(algorithm, name: str, *, information_only: bool = False):
    """Update a VTK algorithm; raise CorruptFileError on any error it reports.

    Parameters
    ----------
    algorithm : vtkAlgorithm
    name : str
        File name for the message.
    information_only : bool
        Only run ``UpdateInformation`` (reads the header, allocates nothing).
    """
    from splineviz.io.errors import CorruptFileError

    # no ErrorEvent observer: an observer would swallow the reader's own message and leave
    # only the executive's generic "returned failure" text in the output window
    with captured_vtk_output() as out:
        ok = algorithm.UpdateInformation() if information_only else algorithm.Update()
    msg = first_vtk_error(out[0] if out else "")
    failed = ok == 0 if isinstance(ok, int) else False
    if msg or failed:
        detail = msg or "the reader reported an error"
        raise CorruptFileError(f"{name} cannot be read: {detail}")


def image_to_array(image, name: str):
    """(nx, ny, nz) NumPy view of the active scalars of a vtkImageData.

    VTK stores samples x-fastest; reshaping to (nz, ny, nx) and transposing gives the
    ``data[i, j, k]`` convention of :class:`~splineviz.Volume` without a copy.
    """
    from vtkmodules.util.numpy_support import vtk_to_numpy

    from splineviz.io.errors import InvalidDataError

    pd = image.GetPointData()
    arr = pd.GetScalars()
    if arr is None:
        for i in range(pd.GetNumberOfArrays()):
            cand = pd.GetArray(i)
            if cand is not None and cand.GetNumberOfComponents() == 1:
                arr = cand
                break
    if arr is None:
        raise InvalidDataError(f"{name} holds no scalar point data")
    if arr.GetNumberOfComponents() != 1:
        raise InvalidDataError(
            f"{name} has {arr.GetNumberOfComponents()} components per sample; only scalar "
            "volumes can be shown as isosurfaces"
        )
    nx, ny, nz = image.GetDimensions()
    flat = vtk_to_numpy(arr)
    if flat.size != nx * ny * nz:
        raise InvalidDataError(
            f"{name} has {flat.size} samples for dimensions {(nx, ny, nz)}"
        )
    return np.asarray(flat).reshape(nz, ny, nx).transpose(2, 1, 0)


_XML_TAG = {name: re.compile(rb"<" + name.encode() + rb"\b([^>]*)>", re.S)
            for name in ("VTKFile", "DataArray", "Piece", "AppendedData")}
_XML_ATTR = re.compile(rb'(\w+)\s*=\s*"([^"]*)"')
#: most blocks a compressed array of a sane file has (VTK's blocks are 32 KiB by default)
MAX_BLOCKS = 2**26
#: most components per tuple: VTK loops over components while it parses a header (2^31 of
#: them hang the reader); real arrays have 1 to 9, field data a few hundred
MAX_COMPONENTS = 4096


def _attrs(text: bytes) -> dict:
    return {k.decode("latin-1"): v.decode("latin-1") for k, v in _XML_ATTR.findall(text)}


def check_xml_appended(path, name: str, budget: int) -> None:
    """Check the binary headers of a VTK XML file's raw appended arrays before VTK reads it.

    VTK's XML readers trust the block table of an appended array: a damaged one (a block
    count or size of 10^9) makes them allocate without limit, and ``std::bad_alloc``
    aborts the whole process. The table is read here (memory-mapped, nothing copied) and
    every array must fit in the file and in ``budget`` bytes once inflated.

    Raises
    ------
    CorruptFileError
        The table does not fit the file or announces more than the budget.
    """
    import mmap

    from splineviz.io.errors import CorruptFileError

    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        if size == 0:
            return
        with mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as m:
            where = m.find(b"<AppendedData")
            head = m[:where] if where >= 0 else m[:min(size, 1 << 20)]
            # VTK allocates a piece's points and cells from these counts before it reads
            # any data: each must be what the file can hold (compressed data inflate at most
            # ~1100:1), or a damaged count of 2*10^9 allocates tens of GB, and a failed
            # allocation aborts the process
            most = min(2**31, 1100 * size + 4096)
            for piece in _XML_TAG["Piece"].findall(head):
                for key, val in _attrs(piece).items():
                    if key.startswith("NumberOf") or key == "Extent":
                        for n in val.split():
                            if not re.fullmatch(r"-?\d{1,12}", n) or abs(int(n)) > most:
                                raise CorruptFileError(f"{name} has the unusable piece size "
                                                       f"{key}={val[:40]!r}")
            for arr in _XML_TAG["DataArray"].findall(head):
                for key in ("NumberOfComponents", "NumberOfTuples"):
                    val = _attrs(arr).get(key)
                    limit = MAX_COMPONENTS if key == "NumberOfComponents" else 2**31
                    if val is not None and (not re.fullmatch(r"\d{1,12}", val.strip())
                                            or int(val) > min(limit, most)):
                        raise CorruptFileError(f"{name} has an array with the unusable "
                                               f"{key}={val[:40]!r}")
            if where < 0:
                return
            tag = _XML_TAG["AppendedData"].match(m[where:where + 4096])
            if tag is None:
                raise CorruptFileError(f"{name} has a damaged AppendedData tag")
            encoded = _attrs(tag.group(1)).get("encoding", "raw") == "base64"
            start = m.find(b"_", where + tag.end())
            if start < 0:
                raise CorruptFileError(f"{name} has no appended data after its header")
            start += 1
            vtkfile = _XML_TAG["VTKFile"].search(head)
            info = _attrs(vtkfile.group(1)) if vtkfile else {}
            hsize = 8 if info.get("header_type") == "UInt64" else 4
            order = ">" if info.get("byte_order") == "BigEndian" else "<"
            compressed = "compressor" in info
            dt = np.dtype(f"{order}u{hsize}")

            def words(at, count):
                """``count`` header words at ``at`` (base64: the header is one chunk)."""
                nbytes = count * hsize
                span = -(-nbytes // 3) * 4 if encoded else nbytes
                if at < start or at + span > size:
                    raise CorruptFileError(f"{name}: an appended array's header lies past the "
                                           "end of the file (truncated or damaged)")
                raw = m[at:at + span]
                if encoded:
                    try:
                        raw = base64.b64decode(raw, validate=True)[:nbytes]
                    except (binascii.Error, ValueError):
                        raise CorruptFileError(f"{name} has damaged base64 appended data") \
                            from None
                return np.frombuffer(raw, dtype=dt, count=count).astype(object)

            for arr in _XML_TAG["DataArray"].findall(head):
                a = _attrs(arr)
                if a.get("format") != "appended":
                    continue
                try:
                    at = start + int(a.get("offset", "0"))
                except ValueError:
                    raise CorruptFileError(f"{name} has an unreadable array offset") from None
                if not compressed:
                    (nbytes,) = words(at, 1)
                    if at + hsize + nbytes > size * (1 + encoded) or nbytes > budget:
                        raise CorruptFileError(f"{name}: array {a.get('Name', '')!r} announces "
                                               f"{nbytes:,} bytes, more than the file holds")
                    continue
                nblocks, bsize, last = words(at, 3)
                if nblocks > MAX_BLOCKS or (nblocks and bsize == 0):
                    raise CorruptFileError(f"{name}: array {a.get('Name', '')!r} has a damaged "
                                           "compression header")
                csizes = words(at, 3 + int(nblocks))[3:]
                total = (nblocks - 1) * bsize + (last or bsize) if nblocks else 0
                # zlib inflates at most ~1032:1; a table announcing more is damaged (and a
                # large enough claim would make VTK's allocation fail and abort)
                if last > bsize or total > budget or total > 1100 * (sum(csizes) + 64) or \
                        at + (3 + nblocks) * hsize + sum(csizes) > size * (1 + encoded):
                    raise CorruptFileError(f"{name}: array {a.get('Name', '')!r} has a damaged "
                                           "compression header (sizes beyond the file or "
                                           "memory)")
