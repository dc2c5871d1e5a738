"""DICOM volumes read with pydicom: series of single-frame images, multi-frame files (enhanced
CT/MR with per-frame functional groups, RT dose grids) and the choice between the series of
a folder.

Opening a folder reads its DICOM series (refused with the list of series when it holds
several: choose one with :func:`series_file`, ``--series`` on the command line or the GUI's
chooser); opening one file reads the series it belongs to among the files of its folder, or
the file alone when it holds several frames.

Geometry: the image-to-patient affine (LPS millimetres, as ITK) is built from
ImageOrientationPatient, PixelSpacing and the slice positions (ImagePositionPatient of each
slice or frame; RT dose: GridFrameOffsetVector along the slice normal) and kept in
``meta["affine"]`` and placed by the rule every reader follows
(:func:`splineviz.io.geometry.axis_aligned`): axes along the patient axes in any order and
sign are transposed and flipped into place with a warning; an oblique grid keeps its
rotation as its direction, never silently made axis-aligned. Slices spaced unevenly (a
missing slice, variable spacing) are resampled to even steps by linear interpolation with a
warning. Values: RescaleSlope/RescaleIntercept (per frame where given) and DoseGridScaling
(per file), in the unit ``meta["value_unit"]`` names (:func:`value_unit`).
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizWarning
from splineviz.io._util import MIN_SAMPLES_PER_AXIS, check_volume_size, confined, held_bytes
from splineviz.io.chunked import is_lazy
from splineviz.io.errors import CorruptFileError, FileFormatError, InvalidDataError
from splineviz.io.geometry import axis_aligned
from splineviz.io.mapped import CHUNK_BYTES, lazy_threshold
from splineviz.io.registry import register_format
from splineviz.io.volume_data import VolumeData

#: slice steps may differ by this fraction of the median step and count as even
EVEN_STEP_TOLERANCE = 1e-3
#: an uneven series is resampled to at most this many times its slice count
MAX_RESAMPLE_FACTOR = 4
#: DoseUnits (3004,0002) as splineviz names them
DOSE_UNITS = {"GY": "Gy", "RELATIVE": "relative"}
#: folder scans kept (header summaries of every file, keyed by the files' sizes and times)
_SCAN_CACHE_SIZE = 8
_scans: dict = {}


class SeriesChoiceError(InvalidDataError):
    """A folder holds several DICOM series and none was chosen (the message lists them)."""


@dataclass(frozen=True)
class Series:
    """One DICOM series of a folder.

    Attributes
    ----------
    uid : str
        SeriesInstanceUID ("" when the files have none).
    number : int or None
        SeriesNumber.
    modality, description : str
    files : tuple of Path
        Its image files, in name order.
    rows, columns, frames : int
        Picture size of its first file and the total number of frames.
    """

    uid: str
    number: int | None
    modality: str
    description: str
    files: tuple
    rows: int
    columns: int
    frames: int

    def short(self) -> str:
        """Modality, number, description and image count."""
        what = " ".join(t for t in (self.modality, f"#{self.number}" if self.number is not None
                                    else "", repr(self.description[:24]) if self.description
                                    else "") if t)
        return f"{what or 'series'}, {self.frames} image(s)"

    def label(self) -> str:
        """One line naming the series for a chooser or a message."""
        what = " ".join(t for t in (self.modality, f"#{self.number}" if self.number is not None
                                    else "", repr(self.description) if self.description
                                    else "") if t)
        return (f"{what or 'series'}: {len(self.files)} file(s), {self.frames} frame(s) of "
                f"{self.columns}x{self.rows} (UID {self.uid or 'none'})")


# ---------------------------------------------------------------------------- recognising
def sniff_dicom(head: bytes) -> bool:
    """A DICOM Part 10 file ("DICM" after the 128-byte preamble), or a bare data set that
    starts with a group 0002 or 0008 element in explicit or implicit VR little endian."""
    if len(head) >= 132 and head[128:132] == b"DICM":
        return True
    if len(head) < 8 or head[:2] not in (b"\x02\x00", b"\x08\x00"):
        return False
    vr = head[4:6]
    if vr.isalpha() and vr.isupper():
        return True
    return int.from_bytes(head[4:8], "little") < 1024


def _is_dicom_file(path: Path) -> bool:
    try:
        with open(path, "rb") as fh:
            return sniff_dicom(fh.read(132))
    except OSError:
        return False


def _header(path: Path):
    """The data set without its pixels, or None when ``path`` is not a DICOM image."""
    import pydicom
    from pydicom.errors import InvalidDicomError

    if not _is_dicom_file(path):
        return None
    try:
        ds = pydicom.dcmread(str(path), stop_before_pixels=True, force=True)
        if "Rows" not in ds or "Columns" not in ds:
            return None
        int(ds.Rows), int(ds.Columns)
    except (InvalidDicomError, EOFError, OSError, ValueError, TypeError, KeyError,
            AttributeError, IndexError):
        return None
    return ds


def _scan(folder: Path) -> list[Series]:
    """The series of the DICOM images in ``folder`` (not its sub-folders), cached while
    no file is added, removed or changed."""
    entries = []
    for f in sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".")):
        # a symbolic link in the series folder must not pull in a file from elsewhere
        confined(f.name, folder / f.name, what="DICOM file", folder=folder)
        st = f.stat()
        entries.append((f.name, st.st_size, st.st_mtime_ns))
    key = (str(folder.resolve()), tuple(entries))
    if key in _scans:
        return _scans[key]
    groups: dict[str, list] = {}
    for name, _, _ in entries:
        ds = _header(folder / name)
        if ds is not None:
            groups.setdefault(str(ds.get("SeriesInstanceUID", "") or ""), []).append(
                (folder / name, ds))
    series = []
    for uid, members in groups.items():
        ds = members[0][1]
        series.append(Series(
            uid, _int_or_none(ds.get("SeriesNumber")), str(ds.get("Modality", "") or ""),
            str(ds.get("SeriesDescription", "") or ""),
            tuple(f for f, _ in members), int(ds.Rows), int(ds.Columns),
            sum(_frames(d) for _, d in members)))
    series.sort(key=lambda s: (s.number is None, s.number or 0, s.uid))
    while len(_scans) >= _SCAN_CACHE_SIZE:
        _scans.pop(next(iter(_scans)))
    _scans[key] = series
    return series


def _int_or_none(value) -> int | None:
    try:
        return int(value)
    except (TypeError, ValueError):
        return None


def _frames(ds) -> int:
    try:
        return max(1, int(ds.get("NumberOfFrames", 1) or 1))
    except (TypeError, ValueError):
        return 1


def list_series(path) -> list[Series]:
    """The DICOM series of a folder, or of the folder of a DICOM file.

    Parameters
    ----------
    path : path-like
        A folder or one of its files.

    Returns
    -------
    list of Series
        Ordered by SeriesNumber, then UID; empty when no file is a DICOM image.
    """
    p = Path(os.fspath(path)).expanduser()
    return _scan(p if p.is_dir() else p.parent)


def series_file(path, choice) -> Path:
    """A file of the chosen series: opening it opens that series.

    Parameters
    ----------
    path : path-like
        A folder (or one of its files).
    choice : str or int
        A SeriesInstanceUID, or the index of the series in :func:`list_series`.

    Raises
    ------
    InvalidDataError
        No such series; the message lists them.
    """
    found = list_series(path)
    text = str(choice).strip()
    for s in found:
        if s.uid and s.uid == text:
            return s.files[0]
    if text.isdigit() and int(text) < len(found):
        return found[int(text)].files[0]
    raise InvalidDataError(f"{Path(os.fspath(path)).name} has no DICOM series {text!r}; "
                           f"its series are {_choices(found)}")


def _choices(found: list[Series]) -> str:
    """The series in a few words each (messages are kept short: ``info`` lists the UIDs)."""
    return "; ".join(f"{n}: {s.short()}" for n, s in enumerate(found))


def describe_series(path) -> dict | None:
    """For ``splineviz info``: the series of a DICOM folder that holds several (None for
    anything else), each as ``"index: label"``."""
    p = Path(os.fspath(path)).expanduser()
    if not p.is_dir():
        return None
    found = _scan(p)
    if len(found) < 2:
        return None
    return {"kind": "DICOM folder", "file": str(p), "format": "dicom",
            "series": [f"{n}: {s.label()}" for n, s in enumerate(found)],
            "choose": "--series UID|index, or open a file of the series"}


# ---------------------------------------------------------------------------- reading
def _read_dicom_folder(path: Path):
    """The DICOM series of a folder; with several, a :class:`SeriesChoiceError` lists
    them."""
    found = _scan(path)
    if not found:
        raise InvalidDataError(f"folder {path.name} holds no DICOM images")
    if len(found) > 1:
        raise SeriesChoiceError(f"folder {path.name} holds {len(found)} DICOM series "
                                f"({_choices(found)}); choose one with --series INDEX|UID or "
                                "open one of its files")
    return _read_series(found[0], path.name)


def _read_dicom_file(path: Path):
    """The volume a DICOM file belongs to: its own frames, or its series in its folder."""
    import pydicom

    ds = _header(path)
    if ds is None:
        try:
            ds = pydicom.dcmread(str(path), stop_before_pixels=True, force=True)
        except Exception as exc:  # noqa: BLE001 - pydicom raises many types on damage
            raise CorruptFileError(f"{path.name} is not a readable DICOM file: "
                                   f"{str(exc).splitlines()[0] if str(exc) else exc}") from None
        raise InvalidDataError(f"{path.name} is a DICOM {_what(ds)} without pixel data, not "
                               "an image volume")
    _refuse_non_scalar(ds, path.name)
    if _frames(ds) > 1:
        return _read_multiframe(path)
    uid = str(ds.get("SeriesInstanceUID", "") or "")
    for s in _scan(path.parent):
        if s.uid == uid and any(f.name == path.name for f in s.files):
            # the single-frame images of its series (a multi-frame file beside them, e.g.
            # an RT dose grid and one of its frames, is a volume of its own)
            return _read_series(s, path.name, single_frames=True)
    raise InvalidDataError(f"{path.name} is not a readable DICOM image")


def _what(ds) -> str:
    sop = ds.get("SOPClassUID") or getattr(getattr(ds, "file_meta", None),
                                           "MediaStorageSOPClassUID", None)
    name = getattr(sop, "name", "") or str(ds.get("Modality", "") or "")
    if name and name != str(sop):
        return name.replace(" Storage", "")
    return f"object of SOP class {sop}" if sop else "object"


def _refuse_non_scalar(ds, name: str) -> None:
    spp = int(ds.get("SamplesPerPixel", 1) or 1)
    photometric = str(ds.get("PhotometricInterpretation", "") or "")
    if spp > 1 or photometric.startswith(("RGB", "YBR", "PALETTE")):
        raise InvalidDataError(f"{name} is a colour ({photometric or 'RGB'}) picture, not a "
                               "volume of scalar samples")


def _pixels(path: Path):
    """The full data set and its decoded pixel array; a missing decoder is named."""
    import pydicom

    try:
        ds = pydicom.dcmread(str(path), force=True)
    except Exception as exc:  # noqa: BLE001
        raise CorruptFileError(f"{path.name} is not a readable DICOM file: {exc}") from None
    if "PixelData" not in ds and "FloatPixelData" not in ds and \
            "DoubleFloatPixelData" not in ds:
        raise InvalidDataError(f"{path.name} is a DICOM {_what(ds)} without pixel data, not "
                               "an image volume")
    try:
        return ds, np.asarray(ds.pixel_array)
    except Exception as exc:  # noqa: BLE001 - pixel handlers raise many types
        text = str(exc)
        ts = getattr(getattr(ds, "file_meta", None), "TransferSyntaxUID", None)
        needs = re.findall(r"-\s*requires\s+(.+)", text)
        if needs or (ts is not None and getattr(ts, "is_compressed", False)
                     and "missing" in text):
            pkgs = "; or ".join(n.strip() for n in needs) or "pylibjpeg or gdcm"
            how = ts.name if ts is not None else "an unknown transfer syntax"
            raise FileFormatError(f"{path.name} is compressed as {how}; install a pydicom "
                                  f"pixel decoder for it: {pkgs}") from None
        detail = text.splitlines()[0] if text else type(exc).__name__
        raise CorruptFileError(f"cannot decode the pixels of {path.name}: {detail}") from None


def _floats(value, n: int, what: str, name: str) -> np.ndarray:
    try:
        arr = np.asarray([float(v) for v in value], dtype=np.float64)
    except (TypeError, ValueError):
        raise CorruptFileError(f"{name} has an unreadable {what}") from None
    if arr.size != n or not np.all(np.isfinite(arr)):
        raise CorruptFileError(f"{name} has an unusable {what} {list(value)}")
    return arr


def _orientation(value, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row and column direction cosines and the slice normal (unit vectors)."""
    iop = _floats(value, 6, "ImageOrientationPatient", name)
    row, col = iop[:3], iop[3:]
    if not (0.9 < np.linalg.norm(row) < 1.1 and 0.9 < np.linalg.norm(col) < 1.1):
        raise CorruptFileError(f"{name} has ImageOrientationPatient {iop.tolist()} whose "
                               "vectors are not unit length")
    row, col = row / np.linalg.norm(row), col / np.linalg.norm(col)
    normal = np.cross(row, col)
    if np.linalg.norm(normal) < 0.9:
        raise CorruptFileError(f"{name} has ImageOrientationPatient {iop.tolist()} whose "
                               "row and column directions are not perpendicular")
    return row, col, normal / np.linalg.norm(normal)


def _pixel_spacing(value, name: str) -> tuple[float, float]:
    """(column step, row step): PixelSpacing is (between rows, between columns)."""
    if value is None:
        return 1.0, 1.0
    ps = _floats(value, 2, "PixelSpacing", name)
    if np.any(ps <= 0):
        raise CorruptFileError(f"{name} has a non-positive PixelSpacing {ps.tolist()}")
    return float(ps[1]), float(ps[0])


def _rescale(ds, seq_item=None) -> tuple[float, float]:
    src = seq_item if seq_item is not None else ds
    try:
        slope = float(src.get("RescaleSlope", 1.0) if src.get("RescaleSlope") is not None
                      else 1.0)
        inter = float(src.get("RescaleIntercept", 0.0) if src.get("RescaleIntercept")
                      is not None else 0.0)
    except (TypeError, ValueError):
        raise CorruptFileError("a DICOM file has an unreadable RescaleSlope or "
                               "RescaleIntercept") from None
    return slope, inter


def _dose_scaling(ds, name: str) -> float | None:
    """DoseGridScaling: the dose of one stored unit (None when the file has none)."""
    value = ds.get("DoseGridScaling")
    if value is None or value == "":
        return None
    try:
        scale = float(value)
    except (TypeError, ValueError):
        raise CorruptFileError(f"{name} has an unreadable DoseGridScaling {value!r}") from None
    if not np.isfinite(scale) or scale <= 0:
        raise CorruptFileError(f"{name} has an unusable DoseGridScaling {scale:g}")
    return scale


def value_unit(ds) -> str | None:
    """The unit of a file's values once scaled: an RT dose's DoseUnits (``"Gy"``, or
    ``"relative"``: a share of an unstated reference dose, never taken for Gy), ``"HU"``
    for CT, else None (unknown)."""
    units = str(ds.get("DoseUnits", "") or "").strip()
    if units or str(ds.get("Modality", "")) == "RTDOSE":
        return DOSE_UNITS.get(units.upper(), units or None)
    if str(ds.get("Modality", "")) == "CT":
        return "HU"
    return None


def _read_series(series: Series, name: str, single_frames: bool = False):
    """A series of single-frame images (or one multi-frame file); ``single_frames``: only
    the single-frame images of the series."""
    if len(series.files) == 1 and series.frames > 1:
        return _read_multiframe(series.files[0])
    heads = [(f, _header(f)) for f in series.files]
    heads = [(f, ds) for f, ds in heads if ds is not None]
    if any(_frames(ds) > 1 for _, ds in heads):
        if not single_frames:
            raise InvalidDataError(f"{name}: series {series.uid or '(no UID)'} mixes "
                                   "multi-frame files with other images; open one of its files")
        heads = [(f, ds) for f, ds in heads if _frames(ds) == 1]
    if len(heads) < MIN_SAMPLES_PER_AXIS:
        raise InvalidDataError(f"{name} is a single 2-D DICOM image (its series has "
                               f"{len(heads)} such image), not a volume")
    first = heads[0][1]
    _refuse_non_scalar(first, heads[0][0].name)
    rows, cols = int(first.Rows), int(first.Columns)
    if any((int(ds.Rows), int(ds.Columns)) != (rows, cols) for _, ds in heads):
        raise InvalidDataError(f"the DICOM images of {name}'s series differ in size")
    iop_value = first.get("ImageOrientationPatient")
    if iop_value is None or any(ds.get("ImagePositionPatient") is None for _, ds in heads):
        raise InvalidDataError(f"the images of {name}'s series have no positions "
                               "(ImageOrientationPatient/ImagePositionPatient), so their "
                               "order and spacing in space are unknown")
    row, col, normal = _orientation(iop_value, name)
    for f, ds in heads[1:]:
        r2, c2, _ = _orientation(ds.get("ImageOrientationPatient", iop_value), f.name)
        if max(np.abs(r2 - row).max(), np.abs(c2 - col).max()) > 1e-3:
            raise InvalidDataError(f"the images of {name}'s series lie in differently "
                                   "oriented planes, not one stack")
    pos = np.array([_floats(ds.ImagePositionPatient, 3, "ImagePositionPatient", f.name)
                    for f, ds in heads])
    spacing_xy = _pixel_spacing(first.get("PixelSpacing"), name)
    order = np.argsort(pos @ normal, kind="stable")
    _check_depths((pos @ normal)[order], name)  # before decoding a single pixel
    units = {value_unit(ds) for _, ds in heads}
    if len(units) > 1:
        raise InvalidDataError(f"the images of {name}'s series hold values in different units "
                               f"({', '.join(sorted(str(u) for u in units))}), not one volume")
    slices = SeriesSlices([heads[i][0] for i in order], rows, cols)
    depth = (pos @ normal)[order]
    steps = np.diff(depth)
    even = np.max(np.abs(steps - np.median(steps))) <= EVEN_STEP_TOLERANCE * np.median(steps)
    if even and held_bytes(slices.shape, slices.dtype) > lazy_threshold():
        stack = slices.lazy()  # read slice by slice as bricks need them
    else:  # whole (uneven slices are resampled, which needs them all)
        check_volume_size((cols, rows, len(heads)), slices.dtype, name)
        stack = slices[:, :, :]
    meta = {"series": series.uid, "modality": series.modality, "value_unit": units.pop(),
            "description": series.description, "files": len(heads)}
    return _volume(stack, pos[order], row, col, normal, spacing_xy, name, meta)


class SeriesSlices:
    """A picklable region reader of a series of single-frame images, stored (slice, row,
    column) in slice order: a region decodes only the files of its slices, each rescaled
    (RescaleSlope/RescaleIntercept, DoseGridScaling) to float32.

    Parameters
    ----------
    files : sequence of path-like
        The images in slice order.
    rows, cols : int
        Their picture size.
    """

    def __init__(self, files, rows: int, cols: int):
        self.files = [str(f) for f in files]
        self.shape = (len(self.files), int(rows), int(cols))
        self.dtype = np.dtype(np.float32)
        self.ndim = 3

    def __getitem__(self, key) -> np.ndarray:
        """The values of ``key`` (three slices), float32, (slices, rows, columns)."""
        key = tuple(key) + (slice(None),) * (3 - len(tuple(key)))
        zs = range(*key[0].indices(self.shape[0]))
        out = np.empty((len(zs),) + tuple(len(range(*k.indices(n))) for k, n in zip(
            key[1:], self.shape[1:], strict=True)), dtype=np.float32)
        for n, z in enumerate(zs):
            f = Path(self.files[z])
            ds, px = _pixels(f)
            if px.shape != self.shape[1:]:
                raise CorruptFileError(f"{f.name} holds pixels of shape {px.shape}, expected "
                                       f"{self.shape[1:]}")
            px = px[key[1:]]
            slope, inter = _rescale(ds)
            out[n] = px * slope + inter if (slope, inter) != (1.0, 0.0) else px
            dose = _dose_scaling(ds, f.name)  # each file of a dose series has its own
            if dose is not None:
                out[n] *= np.float32(dose)
        return out

    def lazy(self):
        """A dask array of the series in chunks of whole slices (about
        :data:`~splineviz.io.mapped.CHUNK_BYTES` each); nothing is read."""
        import dask.array as da

        per_slice = self.shape[1] * self.shape[2] * self.dtype.itemsize
        depth = max(1, min(self.shape[0], CHUNK_BYTES // max(per_slice, 1)))
        return da.from_array(self, chunks=(depth,) + self.shape[1:], asarray=False)


def _functional(ds, frame: int, sequence: str, attr: str):
    """``attr`` of a functional group for one frame: per-frame first, then shared, then the
    data set's top level."""
    for groups, index in (("PerFrameFunctionalGroupsSequence", frame),
                          ("SharedFunctionalGroupsSequence", 0)):
        seq = ds.get(groups)
        if seq is not None and len(seq) > index:
            inner = seq[index].get(sequence)
            if inner is not None and len(inner) and attr in inner[0]:
                return inner[0].get(attr), inner[0]
    return ds.get(attr), None


def _read_multiframe(path: Path):
    """A multi-frame file: enhanced CT/MR/PET (per-frame functional groups), RT dose
    (GridFrameOffsetVector, DoseGridScaling) or a legacy multi-frame with per-frame
    positions."""
    ds, px = _pixels(path)
    name = path.name
    _refuse_non_scalar(ds, name)
    frames = _frames(ds)
    px = px.reshape((frames,) + px.shape[-2:]) if px.ndim in (2, 3) else px
    if px.ndim != 3:
        raise InvalidDataError(f"{name} holds pixels of shape {px.shape}, not frames of a "
                               "scalar volume")
    iop_value, _ = _functional(ds, 0, "PlaneOrientationSequence", "ImageOrientationPatient")
    ps_value, _ = _functional(ds, 0, "PixelMeasuresSequence", "PixelSpacing")
    if iop_value is None:
        raise InvalidDataError(f"{name} holds {frames} frames without an orientation (a cine "
                               "loop or time series?), not a volume")
    row, col, normal = _orientation(iop_value, name)
    offsets = ds.get("GridFrameOffsetVector")
    ipp0 = ds.get("ImagePositionPatient")
    if offsets is not None and ipp0 is not None:
        # RT dose: offsets along the normal, relative to the first frame (when the first
        # offset is 0) or absolute z with the first at ImagePositionPatient: either way
        # frame k lies (offset_k - offset_0) from ImagePositionPatient
        off = _floats(offsets, frames, "GridFrameOffsetVector", name)
        pos = _floats(ipp0, 3, "ImagePositionPatient", name) + np.outer(off - off[0], normal)
    else:
        pos = []
        for k in range(frames):
            value, _ = _functional(ds, k, "PlanePositionSequence", "ImagePositionPatient")
            if value is None:
                raise InvalidDataError(f"{name} holds {frames} frames without per-frame "
                                       "positions (a cine loop or time series?), not a volume")
            pos.append(_floats(value, 3, "ImagePositionPatient", name))
        pos = np.array(pos)
    stack = np.asarray(px, dtype=np.float32)
    scale = _dose_scaling(ds, name)
    if scale is not None:
        stack = stack * np.float32(scale)
    for k in range(frames):
        value, item = _functional(ds, k, "PixelValueTransformationSequence", "RescaleSlope")
        slope, inter = _rescale(ds, item) if item is not None else _rescale(ds)
        if (slope, inter) != (1.0, 0.0):
            stack[k] = stack[k] * np.float32(slope) + np.float32(inter)
    depth = pos @ normal
    order = np.argsort(depth, kind="stable")
    meta = {"series": str(ds.get("SeriesInstanceUID", "") or ""),
            "modality": str(ds.get("Modality", "") or ""), "value_unit": value_unit(ds),
            "frames": frames}
    if "DoseType" in ds or "DoseSummationType" in ds:
        meta["dose"] = " ".join(str(ds.get(k, "") or "").lower()
                                for k in ("DoseType", "DoseSummationType")).strip()
    return _volume(stack[order], pos[order], row, col, normal,
                   _pixel_spacing(ps_value, name), name, meta)


def _volume(stack, pos, row, col, normal, spacing_xy, name: str, meta: dict):
    """VolumeData of slices ``stack`` (n, rows, cols) sorted along ``normal`` at positions
    ``pos`` (n, 3): evenly spaced (resampled if not), axis-aligned by the shared geometry
    rule (:func:`splineviz.io.geometry.axis_aligned`: transposed and flipped with a warning,
    an oblique grid's rotation kept as its direction)."""
    if len(stack) < MIN_SAMPLES_PER_AXIS:
        raise InvalidDataError(f"{name} holds {len(stack)} slice; a volume needs at least "
                               f"{MIN_SAMPLES_PER_AXIS}")
    depth = pos @ normal
    _check_depths(depth, name)
    steps = np.diff(depth)
    dz = float(np.median(steps))
    if np.max(np.abs(steps - dz)) > EVEN_STEP_TOLERANCE * dz:
        stack, dz = _resample(stack, depth, name)
    # slices off the normal through the first one (a gantry tilt) would be sheared
    drift = (pos - pos[0]) - np.outer(depth - depth[0], normal)
    if np.abs(drift).max() > 0.05 * max(min(spacing_xy), 1e-9):
        raise InvalidDataError(f"{name}'s slices are shifted sideways from one to the next "
                               "(a gantry tilt or sheared stack); splineviz reads rectilinear "
                               "grids only")
    affine = np.eye(4)
    affine[:3, 0] = row * spacing_xy[0]
    affine[:3, 1] = col * spacing_xy[1]
    affine[:3, 2] = normal * dz
    affine[:3, 3] = pos[0]
    data = stack.transpose(2, 1, 0)  # (columns, rows, slices)
    # DICOM positions and spacings are millimetres (PS3.3 C.7.6.2)
    meta = {**meta, "affine": affine.tolist(), "space": "LPS", "length_unit": "mm"}
    data, orient = axis_aligned(data, affine, name, space="LPS")
    return VolumeData(data if is_lazy(data) else np.ascontiguousarray(data), orient.spacing,
                      orient.origin, "dicom", meta, orient.volume_direction, "LPS")


def _check_depths(depth, name: str) -> None:
    """Sorted slice depths: two at one position are refused, and so are steps too uneven
    to resample."""
    steps = np.diff(depth)
    if np.any(steps <= 1e-6 * max(1.0, float(np.abs(depth).max()))):
        raise InvalidDataError(f"{name}'s series holds two DICOM slices at the same position "
                               "(copies of one image?), not a stack")
    if len(steps) and float(depth[-1] - depth[0]) / float(steps.min()) + 1 > \
            MAX_RESAMPLE_FACTOR * len(depth):
        raise InvalidDataError(f"{name}'s slices are spaced unevenly ({steps.min():g} to "
                               f"{steps.max():g} mm) beyond what resampling can fill in")


def _resample(stack, depth, name: str):
    """Slices at uneven depths linearly interpolated to even steps (the smallest step, at
    most :data:`MAX_RESAMPLE_FACTOR` times as many slices), with a warning."""
    steps = np.diff(depth)
    span = float(depth[-1] - depth[0])
    n = int(round(span / float(steps.min()))) + 1
    check_volume_size((stack.shape[2], stack.shape[1], n), 4, name)
    targets = depth[0] + np.arange(n) * (span / (n - 1))
    upper = np.clip(np.searchsorted(depth, targets, side="right"), 1, len(depth) - 1)
    lo = upper - 1
    w = ((targets - depth[lo]) / (depth[upper] - depth[lo])).astype(np.float32)
    out = np.empty((n,) + stack.shape[1:], dtype=np.float32)
    for k in range(n):
        out[k] = stack[lo[k]] * (1 - w[k]) + stack[upper[k]] * w[k]
    warnings.warn(f"{name}: the slices are spaced unevenly ({steps.min():g} to "
                  f"{steps.max():g} mm); resampled to {n} slices {span / (n - 1):g} mm apart "
                  "by linear interpolation", SplinevizWarning, stacklevel=2)
    return out, span / (n - 1)


register_format("dicom-file", (".dcm", ".dicom", ".ima"), _read_dicom_file, None,
                kind="volume", sniff=sniff_dicom,
                description="DICOM file (opens its series, or its own frames)")
register_format("dicom", (), _read_dicom_folder, None, kind="volume", folder=True,
                description="DICOM series folder")
