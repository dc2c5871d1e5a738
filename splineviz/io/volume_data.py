"""What a volume reader returns: the samples as stored, with their geometry and frames.

A leaf module (it builds on NumPy and :mod:`splineviz.io.geometry` only) so that the eager
readers (:mod:`splineviz.io.volumes`), the chunked ones (:mod:`splineviz.io.chunked`) and the
format modules share it without importing each other.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from splineviz.io.geometry import affine_from


@dataclass(frozen=True)
class FrameAxis:
    """One non-spatial axis of a 4-D or 5-D file (time, channel, echo, ...).

    Attributes
    ----------
    name : str
        What the axis is, from the file's metadata where it says: ``"time"``,
        ``"channel"``, ``"echo"``, ``"diffusion"``, ... (``"frame"`` when it does not).
    size : int
        Entries along the axis.
    values : tuple of float, optional
        Coordinate of each entry (times, echo times) where the file gives them.
    unit : str
        Unit of ``values`` (``"s"``, ``"ms"``, ...), ``""`` when unknown.
    """

    name: str
    size: int
    values: tuple[float, ...] | None = None
    unit: str = ""


@dataclass
class Frames:
    """The frames of a 4-D (or 5-D) file, read one at a time.

    Attributes
    ----------
    axes : tuple of FrameAxis
        The non-spatial axes in file order (one for 4-D files, two for 5-D).
    read : callable
        ``read(index) -> (n0, n1, n2) ndarray``: the samples of one frame in the file's
        index order (before :class:`~splineviz.io.geometry.Orientation` is applied), where
        ``index`` holds one int per entry of ``axes``. Only that frame is read.
    """

    axes: tuple[FrameAxis, ...]
    read: Callable[[tuple[int, ...]], np.ndarray]

    @property
    def shape(self) -> tuple[int, ...]:
        """Entries along each non-spatial axis."""
        return tuple(a.size for a in self.axes)


@dataclass
class VolumeData:
    """A volume as stored in a file, before conversion to a :class:`~splineviz.Volume`.

    Attributes
    ----------
    data : (n0, n1, n2) ndarray
        Samples in the file's dtype (a view may be non-contiguous); for a 4-D file its
        first frame.
    spacing, origin : (3,) tuple of float
        Step along each array axis and world position of ``data[0, 0, 0]``. A negative
        step runs against its axis (flipped by :func:`~splineviz.io.volumes.to_volume`).
    format : str
        Name of the format that read it.
    meta : dict
        Format-specific extras (e.g. ``{"axis_order": "zxy"}`` for MRC).
    direction : (3, 3) ndarray, optional
        Unit world direction of each array axis (columns), when the file states one that
        is not the identity: with ``spacing`` and ``origin`` it forms the index-to-world
        :attr:`affine`.
    space : str
        World space of the affine: ``"RAS"`` (nibabel formats), ``"LPS"`` (DICOM, most
        MetaImage and NRRD files) or ``""`` when the file does not say.
    frames : Frames, optional
        The frames of a 4-D file (``data`` is the first, or the one chosen).
    """

    data: np.ndarray
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    format: str = ""
    meta: dict = field(default_factory=dict)
    direction: np.ndarray | None = None
    space: str = ""
    frames: Frames | None = None

    @property
    def affine(self) -> np.ndarray:
        """(4, 4) index-to-world affine of ``data`` (file index order)."""
        return affine_from(self.spacing, self.origin, self.direction)
