"""4-D and multi-channel volume files as a sequence of 3-D volumes, read one frame at a time.

fMRI, time-resolved CT, multi-echo and simulation outputs store several volumes in one file.
:func:`read_volume_sequence` opens such a file as a :class:`VolumeSequence`: a lazy sequence of
:class:`~splineviz.Volume` along one non-spatial axis (named, with its times, from the file's
own metadata where it has them), at one chosen channel. A 3-D file is a sequence of one.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from splineviz.io.chunked import is_lazy, to_chunked_volume
from splineviz.io.volume_data import FrameSelection, VolumeData, select_frames
from splineviz.io.volumes import load_volume_data, to_volume, validate_volume_data


class VolumeSequence(Sequence):
    """The volumes of a 4-D file along one axis; ``seq[i]`` reads frame ``i`` only.

    Attributes
    ----------
    name : str
        The file's name.
    axis : FrameAxis
        What the sequence runs along (``axis.name``: ``"time"``, ``"echo"``, ...), with
        the time or other coordinate of each frame in ``axis.values`` where the file gives
        them.
    channel : int or None
        The channel read, for a file with a channel axis.
    channels : int
        Channels in the file (0 when it has no channel axis).
    data : VolumeData
        The first frame as stored, with the file's geometry and format.
    """

    def __init__(self, name: str, data: VolumeData, selection: FrameSelection, options):
        self.name = name
        self.data = data
        self.axis = selection.axis
        self.channel = selection.channel
        self.channels = selection.channels
        self._indices = selection.indices
        self._options = options

    def __len__(self) -> int:
        return len(self._indices)

    def __getitem__(self, i):
        """The Volume of frame ``i`` (negative counts from the end)."""
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        n = len(self)
        k = int(i) + n if int(i) < 0 else int(i)
        if not 0 <= k < n:
            raise IndexError(f"{self.name} has {n} frame(s); frame {i} is not one")
        vd = self.data
        index = self._indices[k]
        if vd.frames is not None and index != vd.meta.get("frame"):
            vd = replace(vd, data=vd.frames.read(index), meta={**vd.meta, "frame": index})
        if is_lazy(vd.data):
            validate_volume_data(vd, self.name)
            return to_chunked_volume(vd, self.name, spacing=self._options.get("spacing"),
                                     origin=self._options.get("origin"),
                                     oblique=self._options.get("oblique", "direction"))
        return to_volume(vd, self.name, **self._options)

    @property
    def times(self) -> tuple[float, ...] | None:
        """Coordinate of each frame along :attr:`axis` (``axis.unit``), if the file says."""
        return self.axis.values

    def __repr__(self) -> str:
        chan = "" if self.channel is None else f", channel {self.channel} of {self.channels}"
        return f"<VolumeSequence {self.name}: {len(self)} along {self.axis.name}{chan}>"


def read_volume_sequence(path, *, channel=None, format=None, spacing=None, origin=None,
                         nonfinite="error", complex="error", oblique="direction",
                         allow_outside=False, **raw) -> VolumeSequence:
    """Open a volume file as a sequence of 3-D volumes, each read when it is indexed.

    Parameters
    ----------
    path : path-like
        Any file :func:`~splineviz.io.volumes.read_volume` reads; 4-D files are NIfTI, MGH,
        MINC, PAR/REC and AFNI (through nibabel).
    channel : int, optional
        The channel to read from a multi-channel file (see
        :func:`~splineviz.io.volume_data.select_frames`): a file with one extra axis gives
        the sequence along it, or with ``channel`` that one channel of it; a 5-D file runs
        along its time axis at ``channel`` (default 0).
    format, spacing, origin, nonfinite, complex, oblique, allow_outside, **raw
        As for :func:`~splineviz.io.volumes.read_volume` (``raw``: ``dims``, ``dtype``,
        ``byteorder``, ``offset`` of headerless files).

    Returns
    -------
    VolumeSequence
        ``len(seq)`` frames; ``seq[i]`` is the :class:`~splineviz.Volume` (x, y, z in the
        file's world space, as :func:`read_volume` gives it) of frame ``i``; ``seq.axis``
        names the axis and holds the frame times where the file has them.

    Raises
    ------
    SplinevizError
        One sentence: the file cannot be read, or ``channel`` does not exist.

    Examples
    --------
    >>> seq = read_volume_sequence("fmri.nii.gz")  # doctest: +SKIP
    >>> len(seq), seq.axis.name, seq.axis.unit, seq[3].shape  # doctest: +SKIP
    (20, 'time', 's', (64, 64, 30))
    """
    name = Path(os.fspath(path)).name
    vd = load_volume_data(path, format=format, allow_outside=allow_outside, channel=channel,
                          **{k: v for k, v in raw.items() if v is not None})
    selection = select_frames(vd.frames, name, channel)
    return VolumeSequence(name, vd, selection,
                          {"spacing": spacing, "origin": origin, "nonfinite": nonfinite,
                           "complex": complex, "oblique": oblique})

