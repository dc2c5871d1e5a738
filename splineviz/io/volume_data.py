"""What a volume reader returns: the samples as stored, with their geometry and frames.

A leaf module (it builds on NumPy and :mod:`splineviz.io.geometry` only) so that the eager
readers (:mod:`splineviz.io.volumes`), the chunked ones (:mod:`splineviz.io.chunked`) and the
format modules share it without importing each other.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from splineviz.io.errors import InvalidDataError
from splineviz.io.geometry import affine_from

#: most frames one file may hold: ten times the longest fMRI runs; a header announcing more
#: (NIfTI-2 allows 2^63 per axis) is refused before frame names or times are built
MAX_FRAMES = 100_000


def check_frame_count(shape, name: str) -> None:
    """Refuse a file whose non-spatial axes (``shape``) hold more than :data:`MAX_FRAMES`
    frames, before anything is built per frame."""
    count = 1
    for n in shape:
        count *= int(n)  # Python ints: no overflow for absurd headers
    if count > MAX_FRAMES:
        raise InvalidDataError(f"{name} announces {count:,} frames {tuple(int(n) for n in shape)}"
                               f"; splineviz reads at most {MAX_FRAMES:,}")


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


@dataclass(frozen=True)
class FrameSelection:
    """Which frames of a 4-D file a volume sequence shows (see :meth:`Frames.select`).

    Attributes
    ----------
    axis : FrameAxis
        The axis the sequence runs along (a one-entry ``"frame"`` axis when a channel was
        chosen from a file whose only extra axis is that channel).
    indices : tuple of tuple of int
        The file index (one int per :attr:`Frames.axes` entry) of each sequence entry.
    channel : int or None
        The channel chosen on the channel axis, if any.
    channels : int
        Entries along the channel axis (0 when there is none).
    """

    axis: FrameAxis
    indices: tuple[tuple[int, ...], ...]
    channel: int | None = None
    channels: int = 0


def select_frames(frames: Frames | None, name: str, channel: int | None = None
                  ) -> FrameSelection:
    """The frames a sequence of ``frames`` runs over, with ``channel`` fixed if given.

    A file with one extra axis runs along it, unless ``channel`` is given: then that axis is
    the channel axis and the sequence holds that one channel. A file with two extra axes
    runs along the one that is not the channel axis (the axis the file names ``"channel"``,
    else the last), at ``channel`` (default 0).

    Parameters
    ----------
    frames : Frames or None
        ``None`` for a 3-D file: one frame, and no channel can be chosen.
    name : str
        File name for messages.
    channel : int, optional

    Raises
    ------
    InvalidDataError
        ``channel`` is out of range, or the file has no extra axis to take it from.
    """
    if frames is None:
        if channel is not None:
            raise InvalidDataError(f"{name} is a 3-D volume with no channel axis; "
                                   f"channel {channel} cannot be chosen")
        return FrameSelection(FrameAxis("frame", 1), ((),))
    axes = frames.axes
    named = [n for n, a in enumerate(axes) if a.name == "channel"]
    if channel is None and len(axes) == 1:
        return FrameSelection(axes[0], tuple((i,) for i in range(axes[0].size)))
    # the channel axis: the one the file calls so, else the last (NumPy's channels-last)
    c = named[0] if named else len(axes) - 1
    chosen = 0 if channel is None else int(channel)
    if not 0 <= chosen < axes[c].size:
        raise InvalidDataError(f"{name} has {axes[c].size} channels (0 to {axes[c].size - 1}) "
                               f"along its {axes[c].name} axis; channel {chosen} is not one")
    rest = [n for n in range(len(axes)) if n != c]
    if not rest:
        return FrameSelection(FrameAxis("frame", 1), ((chosen,),), chosen, axes[c].size)
    s = rest[0]
    indices = []
    for i in range(axes[s].size):
        index = [0] * len(axes)
        index[s], index[c] = i, chosen
        indices.append(tuple(index))
    return FrameSelection(axes[s], tuple(indices), chosen, axes[c].size)
