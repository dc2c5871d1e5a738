"""Open whatever the user gives: a session, a volume (file or DICOM folder) or a point cloud.

This is the dispatch behind ``splineviz FILE|SESSION`` and the GUI's *Open* action.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from splineviz.io.errors import UnknownFormatError

SESSION_SUFFIXES = (".svs",)


@dataclass(frozen=True)
class Opened:
    """What :func:`open_path` found.

    Attributes
    ----------
    kind : {"session", "volume", "points"}
    value : Session, Volume or PointCloud
    path : Path
    """

    kind: str
    value: Any
    path: Path


def data_name(path) -> str:
    """The name a user knows the data at ``path`` by: the file's name, or the store's folder
    when ``path`` is the metadata file of a Zarr store (``scan.zarr/zarr.json`` is
    "scan.zarr")."""
    from splineviz.io.chunked import ZARR_METADATA

    p = Path(os.fspath(path))
    if p.name in (*ZARR_METADATA, ".zattrs") and p.parent.name:
        return p.parent.name
    return p.name


def open_path(path, *, repoint=None, allow_outside: bool = False, **volume_options) -> Opened:
    """Read ``path`` as a session (``.svs``), else as a volume, else as a point cloud.

    Parameters
    ----------
    path : path-like
    repoint : callable, optional
        Passed to :func:`~splineviz.io.session.load_session` for missing data files.
    allow_outside : bool
        Read data files that a header or session names outside its own folder (refused by
        default with an :class:`~splineviz.io.errors.OutsideFolderError`).
    **volume_options
        Passed to :func:`~splineviz.io.volumes.read_volume` for a volume (``channel``,
        ``oblique``; ``dims``, ``dtype``, ``byteorder``, ``offset`` of a headerless raw
        volume, ...).

    Raises
    ------
    SplinevizError
        The reader's specific error; an unknown format names both volume and point formats.
    """
    from splineviz.io.points import read_points
    from splineviz.io.registry import formats
    from splineviz.io.session import load_session
    from splineviz.io.volumes import read_volume

    p = Path(os.fspath(path)).expanduser()
    if p.suffix.lower() in SESSION_SUFFIXES:
        return Opened("session", load_session(p, repoint=repoint,
                                                    allow_outside=allow_outside), p)
    try:
        return Opened("volume", read_volume(p, allow_outside=allow_outside, **volume_options),
                      p)
    except UnknownFormatError:
        pass
    try:
        return Opened("points", read_points(p), p)
    except UnknownFormatError:
        names = ", ".join(f.name for k in ("volume", "points") for f in formats(k))
        raise UnknownFormatError(f"cannot tell the format of {p.name}; readable formats: "
                                 f"{names}, and .svs sessions") from None
