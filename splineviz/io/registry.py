"""The format registry: which reader or writer handles a file.

A :class:`Format` has a name, a kind (``"volume"``, ``"points"``, ``"mesh"`` or
``"image"``), the file-name endings it owns, an optional reader and writer, and an optional
``sniff(head: bytes) -> bool`` that recognises the format from the first :data:`SNIFF_BYTES`
bytes. Lookup goes by suffix first; when the suffix is unknown, or the content contradicts it
(e.g. a PNG renamed ``.nrrd``), the content decides. Plugins add formats with
:func:`register_format`; :data:`FORMATS` is a :class:`~splineviz.core.registry.Registry`, so
listing or looking up formats loads the plugins first.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from splineviz.core.registry import Registry
from splineviz.io.errors import CorruptFileError, UnknownFormatError

#: bytes read from the start of a file to recognise its format
SNIFF_BYTES = 1024

KINDS = ("volume", "points", "mesh", "image")


@dataclass(frozen=True)
class Format:
    """One registered file format.

    Attributes
    ----------
    name : str
        Short unique name within its kind, e.g. ``"nrrd"``.
    kind : str
        ``"volume"``, ``"points"``, ``"mesh"`` or ``"image"``.
    extensions : tuple of str
        Lower-case endings with the dot, e.g. ``(".nii", ".nii.gz")``.
    reader, writer : callable or None
        ``reader(path, **options)`` and ``writer(path, data, **options)``.
    sniff : callable or None
        ``sniff(head: bytes) -> bool`` on the first bytes of a file; for a folder format
        ``sniff(path) -> bool`` on the folder.
    folder : bool
        The format is a folder of files (DICOM series).
    description : str
    """

    name: str
    kind: str
    extensions: tuple[str, ...]
    reader: Callable | None = None
    writer: Callable | None = None
    sniff: Callable[[bytes], bool] | None = None
    folder: bool = False
    description: str = ""
    plugin: str | None = field(default=None, compare=False)


#: (kind, name) -> Format
FORMATS: Registry[Format] = Registry("format", error=UnknownFormatError,
                                     describe=lambda key: f"{key[1]!r} ({key[0]})")


def register_format(name, extensions, reader=None, writer=None, *, kind, sniff=None,
                    folder=False, description="", plugin=None, replace=False) -> Format:
    """Add a format to the registry and return it.

    Parameters
    ----------
    name : str
    extensions : sequence of str
        File endings (with or without the dot; case is ignored).
    reader, writer : callable, optional
    kind : {"volume", "points", "mesh", "image"}
    sniff : callable, optional
    folder : bool
    description : str
    plugin : str, optional
        Name of the plugin that registered it (for error reports).
    replace : bool
        Allow replacing an existing format of the same kind and name.
    """
    if kind not in KINDS:
        raise ValueError(f"format kind must be one of {KINDS}, got {kind!r}")
    if not isinstance(name, str) or not name:
        raise ValueError("a format needs a non-empty name")
    if reader is None and writer is None:
        raise ValueError(f"format {name!r} needs a reader or a writer")
    exts = tuple(
        (e if e.startswith(".") else "." + e).lower() for e in ([extensions] if isinstance(
            extensions, str) else extensions)
    )
    fmt = Format(name, kind, exts, reader, writer, sniff, bool(folder), description, plugin)
    return FORMATS.register((kind, name), fmt, replace=replace)


def formats(kind: str, *, mode: str = "read") -> list[Format]:
    """Registered formats of ``kind`` that can ``mode`` (``"read"`` or ``"write"``), plugin
    formats included."""
    attr = "reader" if mode == "read" else "writer"
    return [f for (k, _), f in FORMATS.entries().items()
            if k == kind and getattr(f, attr) is not None]


def _names(kind: str, mode: str) -> str:
    return ", ".join(
        f"{f.name} ({' '.join(f.extensions)})" if f.extensions else f.name
        for f in formats(kind, mode=mode)
    )


def _by_suffix(path: Path, kind: str, mode: str) -> list[Format]:
    low = path.name.lower()
    hits = [(max(len(e) for e in f.extensions if low.endswith(e)), f)
            for f in formats(kind, mode=mode) if any(low.endswith(e) for e in f.extensions)]
    hits.sort(key=lambda t: -t[0])  # the longest ending wins: ".nii.gz" before ".gz"
    return [f for _, f in hits]


def read_head(path: Path, n: int = SNIFF_BYTES) -> bytes:
    """The first ``n`` bytes of a regular file (a FIFO or device is refused, never waited
    on)."""
    from splineviz.io._util import open_regular

    with open_regular(path) as fh:
        return fh.read(n)


def find_format(path, kind: str, *, mode: str = "read", name: str | None = None) -> Format:
    """The format that reads (or writes) ``path``.

    Parameters
    ----------
    path : path-like
        For reading it must exist (check with :func:`splineviz.io._util.regular_input`).
    kind : str
    mode : {"read", "write"}
    name : str, optional
        Force a format by name.

    Raises
    ------
    UnknownFormatError
        Neither suffix nor content matches; the message lists the valid formats.
    CorruptFileError
        The suffix names a format whose signature the content does not have, and no other
        format recognises the content.
    """
    path = Path(os.fspath(path))
    if name is not None:
        fmt = FORMATS.lookup((kind, name), None)
        if fmt is None or (fmt.reader if mode == "read" else fmt.writer) is None:
            raise UnknownFormatError(
                f"no {kind} format {name!r} can {mode}; valid formats: {_names(kind, mode)}"
            )
        return fmt
    if mode == "read" and path.is_dir():
        # folder formats: by suffix (".zarr"), then by content (``sniff(path)`` of a folder
        # format looks at the folder), then one without a signature (a DICOM series)
        folders = [f for f in formats(kind, mode=mode) if f.folder]
        low = path.name.lower()
        for fmt in sorted(folders, key=lambda f: f.sniff is None):
            if any(low.endswith(e) for e in fmt.extensions) or (
                    fmt.sniff is not None and fmt.sniff(path)):
                return fmt
        for fmt in folders:
            if fmt.sniff is None:
                return fmt
        raise UnknownFormatError(f"{path} is a folder and no {kind} format reads folders")
    candidates = [f for f in _by_suffix(path, kind, mode) if not f.folder]
    if mode == "write":
        if not candidates:
            raise UnknownFormatError(
                f"cannot write {kind} file {path.name}: unknown suffix; valid formats: "
                f"{_names(kind, mode)}"
            )
        return candidates[0]
    head = read_head(path)
    for fmt in candidates:
        if fmt.sniff is None or fmt.sniff(head):
            return fmt
    # the suffix is unknown or lies: let the content decide
    for fmt in formats(kind, mode=mode):
        if fmt.sniff is not None and not fmt.folder and fmt.sniff(head):
            return fmt
    if candidates:
        raise CorruptFileError(
            f"{path.name} does not start like a {candidates[0].name.upper()} file "
            "(wrong or damaged header)"
        )
    raise UnknownFormatError(
        f"cannot tell the format of {path.name}; valid {kind} formats: {_names(kind, mode)}"
    )
