"""VTK plumbing for the readers: error capture and image-to-array conversion.

VTK reports problems through its output window instead of raising. :func:`run_vtk` swaps in
a string output window for the duration of one pipeline update and turns any error text into
a :class:`~splineviz.io.errors.CorruptFileError`, so a damaged file never prints noise and
never passes silently.
"""

from __future__ import annotations

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
