"""Volume readers and writers.

Convention: every reader returns a :class:`~splineviz.io.volume_data.VolumeData` whose
``data`` is indexed ``data[i, j, k]`` at world point ``origin + D @ ((i, j, k) * spacing)``
(x fastest in the file; ``D`` its direction matrix, the identity unless the file states
one), in the file's own sample type; :func:`read_volume` turns it into a
:class:`~splineviz.Volume` that keeps that type where it can (8- and 16-bit integers,
float32), placed by the rule of :mod:`splineviz.io.geometry`. NumPy, raw, raw-encoded
NRRD and MRC samples are memory-mapped; a volume too large to render in one piece
(:func:`~splineviz.io.mapped.renders_in_pieces`) opens as a chunked volume read from the
mapping brick by brick.
Readers are built on VTK (VTI, legacy VTK, MetaImage, multi-file NRRD), pynrrd (NRRD/NHDR),
mrcfile (MRC/CCP4) and pydicom (DICOM series); the nibabel formats live in
:mod:`splineviz.io.neuro`, 4-D files read as sequences in :mod:`splineviz.io.sequence`. SLC
is decoded with NumPy (VTK's reader leaves samples uninitialised). Every header is checked
against the memory budget *before* the payload is allocated, and against the payload size
where the payload is uncompressed.
"""

from __future__ import annotations

import os
import re
import warnings
import zlib
from dataclasses import replace
from pathlib import Path

import numpy as np

from splineviz.core.errors import SplinevizWarning
from splineviz.core.units import canonical_unit
from splineviz.core.volume import Volume, VolumeError, slabs
from splineviz.io import _vtk
from splineviz.io._util import (
    MIN_SAMPLES_PER_AXIS,
    as_float_triplet,
    atomic_output,
    check_volume_size,
    confined,
    memory_budget,
    open_regular,
    outside_allowed,
    reader_errors,
    regular_input,
)
from splineviz.io.chunked import AxisSource, is_lazy, to_chunked_volume
from splineviz.io.errors import (
    CorruptFileError,
    DataFileNotFoundError,
    DataSizeError,
    FileFormatError,
    InvalidDataError,
)
from splineviz.io.geometry import (
    OBLIQUE_MODES,
    affine_from,
    check_oblique,
    orientation,
    resample_axis_aligned,
    warn_flips,
)
from splineviz.io.mapped import MappedArray, lazy_array, renders_in_pieces
from splineviz.io.registry import find_format, register_format
from splineviz.io.volume_data import (
    FrameAxis,
    Frames,
    VolumeData,
    check_frame_count,
    select_frames,
)


# ---------------------------------------------------------------------------- VTK-based
def _vtk_itemsize(reader) -> int:
    """Bytes per sample announced in a VTK reader's pipeline information (8 if unknown)."""
    from vtkmodules.util.numpy_support import get_vtk_to_numpy_typemap
    from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkDataSetAttributes

    info = reader.GetOutputInformation(0)
    field_info = vtkDataObject.GetActiveFieldInformation(
        info, vtkDataObject.FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes.SCALARS
    )
    if field_info is not None and field_info.Has(vtkDataObject.FIELD_ARRAY_TYPE()):
        typ = field_info.Get(vtkDataObject.FIELD_ARRAY_TYPE())
        ncomp = 1
        if field_info.Has(vtkDataObject.FIELD_NUMBER_OF_COMPONENTS()):
            ncomp = max(1, field_info.Get(vtkDataObject.FIELD_NUMBER_OF_COMPONENTS()))
        dt = get_vtk_to_numpy_typemap().get(typ)
        if dt is not None:
            return np.dtype(dt).itemsize * ncomp
    return 8


def _read_with_vtk(reader, path: Path, fmt: str) -> VolumeData:
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline

    reader.SetFileName(str(path))
    _vtk.run_vtk(reader, path.name, information_only=True)
    info = reader.GetOutputInformation(0)
    ext = info.Get(vtkStreamingDemandDrivenPipeline.WHOLE_EXTENT()) if info else None
    if not ext or len(ext) != 6:
        raise CorruptFileError(f"{path.name} has no readable image extent in its header")
    dims = [ext[2 * a + 1] - ext[2 * a] + 1 for a in range(3)]
    if min(dims) < 1:
        raise InvalidDataError(f"{path.name} announces an empty grid of {tuple(dims)} samples")
    check_volume_size(dims, _vtk_itemsize(reader), path.name)
    _vtk.run_vtk(reader, path.name)
    image = reader.GetOutput()
    got = image.GetDimensions()
    if tuple(got) != tuple(dims) or image.GetNumberOfPoints() == 0:
        raise CorruptFileError(
            f"{path.name} announces {tuple(dims)} samples but only {tuple(got)} could be read"
        )
    data = _vtk.image_to_array(image, path.name)
    m = image.GetDirectionMatrix()
    direction = np.array([[m.GetElement(i, j) for j in range(3)] for i in range(3)])
    return VolumeData(data, tuple(image.GetSpacing()), tuple(image.GetOrigin()), fmt, {},
                      None if np.array_equal(direction, np.eye(3)) else direction)


def _read_vti(path: Path) -> VolumeData:
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader

    _vtk.check_xml_appended(path, path.name, memory_budget())
    return _read_with_vtk(vtkXMLImageDataReader(), path, "vti")


def _read_legacy_vtk(path: Path) -> VolumeData:
    from vtkmodules.vtkIOLegacy import vtkStructuredPointsReader

    if b"STRUCTURED_POINTS" not in _head(path, 1024).upper():
        raise FileFormatError(
            f"{path.name} is a legacy VTK file but not STRUCTURED_POINTS image data"
        )
    reader = vtkStructuredPointsReader()
    reader.ReadAllScalarsOn()
    return _read_with_vtk(reader, path, "vtk")


#: the SLC header: magic, dimensions and bits, spacing, unit/origin/modification/compression
_SLC_HEADER = re.compile(rb"\s*11111\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\S+)\s+(\S+)\s+(\S+)"
                         rb"\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s*X")
_SLC_SLICE = re.compile(rb"\s*(\d+)\s*X")
#: the SLC unit codes (VolVis' SLCUnitType: meter, millimeter, micron, foot, inch)
_SLC_UNITS = ("m", "mm", "µm", "ft", "in")


def _slc_decode(run: bytes, size: int, name: str, z: int) -> np.ndarray:
    """One slice of SLC 8-bit run-length code: a byte ``n | 0x80`` is followed by ``n``
    literal bytes, a byte ``n`` by one byte repeated ``n`` times; ``0`` ends the slice.
    Samples the code does not reach are 0 (VTK's reader leaves them uninitialised)."""
    out = np.zeros(size, dtype=np.uint8)
    pos = at = 0
    while pos < len(run):
        head = run[pos]
        n = head & 0x7F
        if n == 0:
            break
        if at + n > size:
            raise CorruptFileError(f"{name}: slice {z} decodes to more than {size} samples")
        if head & 0x80:
            out[at:at + n] = np.frombuffer(run, np.uint8, n, pos + 1)
            pos += 1 + n
        else:
            out[at:at + n] = run[pos + 1]
            pos += 2
        at += n
    return out


def _read_slc(path: Path) -> VolumeData:
    """SLC (Stony Brook) volumes, 8 bits, raw or run-length coded, read with NumPy: VTK's
    reader leaves the part of a slice its code does not cover uninitialised, so the same file
    read twice could give two volumes."""
    raw = path.read_bytes()
    m = _SLC_HEADER.match(raw)
    if m is None:
        raise CorruptFileError(f"{path.name} does not have a valid SLC header")
    nx, ny, nz, bits = (int(m.group(i)) for i in range(1, 5))
    try:
        spacing = tuple(float(m.group(i)) for i in range(5, 8))
    except ValueError:
        raise CorruptFileError(f"{path.name} has an unreadable SLC spacing") from None
    compression, icon_w, icon_h = int(m.group(11)), int(m.group(12)), int(m.group(13))
    if bits != 8:
        raise FileFormatError(f"{path.name} has {bits}-bit samples; SLC volumes of 8 bits "
                              "are supported")
    if compression not in (0, 1):
        raise FileFormatError(f"{path.name} uses SLC compression {compression}; only raw (0) "
                              "and run-length (1) are supported")
    if min(nx, ny, nz) < 1:
        raise InvalidDataError(f"{path.name} announces an empty grid of {(nx, ny, nz)} samples")
    check_volume_size((nx, ny, nz), 1, path.name)
    pos = m.end() + 3 * icon_w * icon_h  # the icon: three planes of icon_w x icon_h bytes
    size = nx * ny
    data = np.empty((nz, ny, nx), dtype=np.uint8)
    for z in range(nz):
        s = _SLC_SLICE.match(raw, pos)
        if s is None:
            raise CorruptFileError(f"{path.name} ends before slice {z} of {nz}")
        n = int(s.group(1))
        pos = s.end()
        chunk = raw[pos:pos + n]
        if len(chunk) < n:
            raise CorruptFileError(f"{path.name} ends inside slice {z} of {nz}")
        pos += n
        if compression:
            data[z] = _slc_decode(chunk, size, path.name, z).reshape(ny, nx)
        elif n != size:
            raise CorruptFileError(f"{path.name}: slice {z} holds {n} bytes, not {size}")
        else:
            data[z] = np.frombuffer(chunk, np.uint8).reshape(ny, nx)
    code = int(m.group(8))
    unit = _SLC_UNITS[code] if code < len(_SLC_UNITS) else ""
    return VolumeData(data.transpose(2, 1, 0), spacing, (0.0, 0.0, 0.0), "slc",
                      {"length_unit": unit})


_MHD_KEY = re.compile(rb"^\s*(\w+)\s*=\s*(.*?)\s*$", re.M)


def _read_metaimage(path: Path) -> VolumeData:
    """MetaImage (.mhd + .raw/.zraw, or .mha) through VTK's vtkMetaImageReader.

    The header is looked at once before VTK reads it to catch what VTK would silently accept:
    a missing data file and, for uncompressed payloads, a size that does not match DimSize.
    """
    head = _head(path, 65536)
    keys = {k.decode("latin-1").lower(): v.decode("latin-1")
            for k, v in _MHD_KEY.findall(head.split(b"ElementDataFile")[0] + b"\n")}
    m = re.search(rb"ElementDataFile\s*=\s*(.*?)\s*$", head, re.M)
    if m is None:
        raise CorruptFileError(f"{path.name} has no ElementDataFile entry")
    datafile = m.group(1).decode("latin-1")
    ndims = keys.get("ndims", "3").strip()
    if ndims != "3":
        raise InvalidDataError(f"{path.name} is a {ndims}-D MetaImage, not a volume")
    try:
        dims = [int(v) for v in keys.get("dimsize", "").split()]
    except ValueError:
        raise CorruptFileError(f"{path.name} has a malformed DimSize") from None
    etype = keys.get("elementtype", "").strip().upper()
    size = _MET_SIZES.get(etype)
    if len(dims) == 3 and size:
        check_volume_size(dims, size, path.name)
    kind = datafile.split()[0].upper() if datafile.split() else ""
    inflated = None
    compressed = keys.get("compresseddata", "false").strip().lower() == "true"
    if kind == "LOCAL":
        if len(dims) == 3 and size and compressed:
            start = head.find(b"\n", m.end())
            if start < 0:
                raise CorruptFileError(f"{path.name} ends at its ElementDataFile line")
            inflated = _inflate_payload(path, dims[0] * dims[1] * dims[2] * size, start + 1)
    elif kind == "LIST" or "%" in datafile:
        # one file per slice: every name is checked (count first, so a pattern bomb is
        # refused before any name is built) against the header's folder
        if len(dims) != 3:
            raise CorruptFileError(f"{path.name} has a malformed DimSize")
        if kind == "LIST":
            names = _listed_names(path, rb"^\s*ElementDataFile\s*=[^\n]*\n")
        else:
            names = _pattern_names(path, datafile.split(), dims[2])
        if len(names) != dims[2]:
            raise DataSizeError(f"{path.name} lists {len(names)} slice files for {dims[2]} "
                                "slices")
        for name in names:
            regular_input(confined(name, path, what="slice file"))
    else:
        payload = regular_input(confined(datafile, path))
        if len(dims) == 3 and size and compressed:
            inflated = _inflate_payload(payload, dims[0] * dims[1] * dims[2] * size)
        if len(dims) == 3 and size and not compressed:
            need = dims[0] * dims[1] * dims[2] * size
            have = payload.stat().st_size
            if have < need:
                raise DataSizeError(
                    f"{payload.name} holds {have} bytes but DimSize {tuple(dims)} of {etype} "
                    f"needs {need}"
                )
    from vtkmodules.vtkIOImage import vtkMetaImageReader  # after the checks: VTK is ~60 MB

    if inflated is None:
        vd = _read_with_vtk(vtkMetaImageReader(), path, "metaimage")
    else:
        # MetaIO inflates only CompressedDataSize bytes of the stream and leaves the rest of
        # the grid uninitialised when the header understates it (frogtissue.mhd does): the
        # samples are those of the whole stream, inflated here once; VTK reads the header
        vd = _metaimage_samples(vtkMetaImageReader(), path, inflated, dims, etype, keys)
    try:
        signs = [np.sign(float(v)) for v in keys.get("elementspacing", "").split()]
    except ValueError:
        signs = []
    if len(signs) == 3 and min(signs) < 0:
        # VTK's reader drops the sign of ElementSpacing: keep it, to_volume flips the axis
        vd.spacing = tuple(-s if g < 0 else s for s, g in zip(vd.spacing, signs, strict=True))
    vd.direction = _metaimage_direction(keys, path.name)
    vd.space = "LPS"  # MetaIO's (ITK's) patient space
    return vd


def _metaimage_direction(keys: dict, name: str):
    """The direction matrix of a MetaImage header (``TransformMatrix``, or its synonyms
    ``Rotation``/``Orientation``), or None for the identity.

    As ITK's MetaImageIO reads it, the k-th triple of numbers is the world direction of
    array axis k, i.e. column k. (VTK 9.7's vtkMetaImageReader returns the transpose, which
    differs from ITK's reading, and from Slicer's, for a non-symmetric matrix.)
    """
    text = next((keys[k] for k in ("transformmatrix", "rotation", "orientation")
                 if k in keys), None)
    if text is None:
        return None
    try:
        values = np.array([float(v) for v in text.split()], dtype=float)
    except ValueError:
        raise CorruptFileError(f"{name} has a malformed TransformMatrix {text[:60]!r}") from None
    if values.size != 9 or not np.all(np.isfinite(values)):
        raise CorruptFileError(f"{name} has a TransformMatrix of {values.size} numbers, not "
                               "a finite 3x3 matrix")
    direction = values.reshape(3, 3).T
    return None if np.array_equal(direction, np.eye(3)) else direction


def _inflate_payload(payload: Path, need: int, offset: int = 0) -> np.ndarray:
    """The ``(need,)`` uint8 bytes of a MetaImage's zlib stream (a .zraw file, or what follows
    ``ElementDataFile = LOCAL`` at ``offset``), inflated chunk by chunk into one buffer; a
    damaged stream, or one that does not inflate to exactly DimSize's bytes, is refused (VTK's
    MetaIO accepts both silently)."""
    out = np.empty(need, dtype=np.uint8)
    inflater = zlib.decompressobj()
    got = 0

    def put(block: bytes) -> None:
        nonlocal got
        if got + len(block) > need:
            raise DataSizeError(f"{payload.name} inflates to more than the {need} bytes "
                                "DimSize needs")
        out[got:got + len(block)] = np.frombuffer(block, np.uint8)
        got += len(block)

    try:
        with open(payload, "rb") as fh:
            fh.seek(offset)
            while chunk := fh.read(1 << 20):
                put(inflater.decompress(chunk))
        put(inflater.flush())
    except zlib.error as exc:
        raise CorruptFileError(f"{payload.name} is a damaged compressed stream: {exc}") from None
    if got != need:
        raise DataSizeError(f"{payload.name} inflates to {got} bytes but DimSize needs {need}")
    return out


def _metaimage_samples(reader, path: Path, inflated: np.ndarray, dims, etype: str,
                       keys: dict) -> VolumeData:
    """VolumeData of a compressed MetaImage from its inflated ``(n,)`` bytes, with the
    spacing and origin VTK reads from the header (the same as a full VTK read gives)."""
    from vtkmodules.vtkCommonDataModel import vtkDataObject

    channels = keys.get("elementnumberofchannels", "1").strip()
    if channels != "1":
        raise InvalidDataError(f"{path.name} has {channels} components per sample; only "
                               "scalar volumes can be shown as isosurfaces")
    reader.SetFileName(str(path))
    _vtk.run_vtk(reader, path.name, information_only=True)
    info = reader.GetOutputInformation(0)
    msb = any(keys.get(k, "false").strip().lower() == "true"
              for k in ("binarydatabyteordermsb", "elementbyteordermsb"))
    dtype = np.dtype(_MET_TYPES[etype]).newbyteorder(">" if msb else "<")
    data = inflated.view(dtype)
    if not dtype.isnative:
        data = data.astype(dtype.newbyteorder("="))
    data = data.reshape(dims[::-1]).transpose(2, 1, 0)
    spacing = tuple(info.Get(vtkDataObject.SPACING()) or (1.0, 1.0, 1.0))
    origin = tuple(info.Get(vtkDataObject.ORIGIN()) or (0.0, 0.0, 0.0))
    return VolumeData(data, spacing, origin, "metaimage", {})


#: MetaIO element types as NumPy types (MET_LONG and MET_ULONG are 64-bit in MetaIO)
_MET_TYPES = {"MET_UCHAR": "u1", "MET_CHAR": "i1", "MET_USHORT": "u2", "MET_SHORT": "i2",
              "MET_UINT": "u4", "MET_INT": "i4", "MET_FLOAT": "f4", "MET_DOUBLE": "f8",
              "MET_ULONG": "u8", "MET_LONG": "i8", "MET_ULONG_LONG": "u8", "MET_LONG_LONG": "i8"}
_MET_SIZES = {name: np.dtype(t).itemsize for name, t in _MET_TYPES.items()}


# ---------------------------------------------------------------------------- NRRD
def _read_nrrd(path: Path) -> VolumeData:
    """NRRD/NHDR with pynrrd; for multi-file data (``data file: name.%d 1 93 1`` or
    ``LIST``), which ``nrrd.read`` does not handle, each slice file is decoded with pynrrd's
    ``read_data``."""
    import nrrd

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            header = nrrd.read_header(str(path))
    except (nrrd.NRRDError, ValueError, TypeError, KeyError, UnicodeDecodeError) as exc:
        raise CorruptFileError(f"{path.name} has a malformed NRRD header: {exc}") from None
    missing = [k for k in ("type", "dimension", "sizes", "encoding") if k not in header]
    if missing:
        raise CorruptFileError(f"{path.name} lacks the required NRRD field(s) "
                               f"{', '.join(missing)}")
    sizes = [int(s) for s in np.atleast_1d(header.get("sizes", []))]
    spatial = _nrrd_spatial_axes(path, header, sizes)
    check_frame_count([n for a, n in enumerate(sizes) if a not in spatial], path.name)
    try:
        itemsize = np.dtype(nrrd.reader._determine_datatype(header)).itemsize
    except (KeyError, TypeError, ValueError, nrrd.NRRDError):
        raise CorruptFileError(f"{path.name} has the unknown NRRD sample type "
                               f"{header.get('type')!r}") from None
    check_volume_size(sizes, itemsize, path.name)
    datafile = str(header.get("data file", header.get("datafile", "")))
    multifile = datafile and (datafile.upper().startswith("LIST") or "%" in datafile)
    spacing, direction = (1.0, 1.0, 1.0), None
    if "space directions" in header:
        dirs = np.asarray(header["space directions"], dtype=float)
        if dirs.shape != (len(sizes), 3) or not np.all(np.isfinite(dirs[spatial])):
            raise CorruptFileError(f"{path.name} has space directions that are not three "
                                   "finite 3-vectors")
        dirs = dirs[spatial]
        # row a of pynrrd's matrix is the world step of array axis a: the affine's column a
        steps = np.linalg.norm(dirs, axis=1)
        if not np.all(steps > 0):
            raise InvalidDataError(f"{path.name} has a zero space direction")
        spacing = tuple(float(v) for v in steps)
        direction = dirs.T / steps[None, :]
        if np.array_equal(direction, np.eye(3)):
            direction = None
    elif "spacings" in header:
        spacing = tuple(float(np.asarray(header["spacings"], dtype=float)[a]) for a in spatial)
    origin = tuple(float(v) for v in header.get("space origin", (0.0, 0.0, 0.0)))
    # "space units" names one unit per world axis; a grid has one length unit
    unit = canonical_unit((header.get("space units") or [""])[0])
    source = None
    if len(sizes) == 3 and not multifile and direction is None:
        source = _nrrd_mapped(path, header, datafile, sizes)
    if source is not None:
        return VolumeData(lazy_array(source), spacing, origin, "nrrd",
                          {"levels": (), "source": source, "length_unit": unit}, None,
                          _NRRD_SPACES.get(str(header.get("space", "")).lower(), ""))
    if multifile:
        if len(sizes) != 3:
            raise FileFormatError(f"{path.name} is a {len(sizes)}-D NRRD in several files; "
                                  "only 3-D multi-file NRRDs are supported")
        data = _read_nrrd_multifile(path, header, datafile, sizes)
    else:
        data, _ = _read_nrrd_single(path, datafile)
    frames = None
    if len(sizes) > 3:
        extra = [a for a in range(len(sizes)) if a not in spatial]
        order = list(spatial) + extra
        full = np.transpose(data, order)  # spatial axes first, in file order

        def read(index):
            return full[(slice(None),) * 3 + tuple(int(i) for i in index)]

        frames = Frames(tuple(_nrrd_frame_axis(header, a, sizes[a]) for a in extra), read)
        data = read((0,) * len(extra))
    return VolumeData(data, spacing, origin, "nrrd", {"length_unit": unit}, direction,
                      _NRRD_SPACES.get(str(header.get("space", "")).lower(), ""), frames)


#: NRRD kinds whose axis holds the components of one sample: a channel axis
_NRRD_CHANNEL_KINDS = {"rgb-color", "rgba-color", "hsv-color", "xyz-color", "vector",
                       "covariant-vector", "normal", "2-vector", "3-vector", "4-vector",
                       "quaternion", "complex", "2d-symmetric-matrix", "3d-symmetric-matrix",
                       "3d-matrix", "2d-matrix"}


def _nrrd_spatial_axes(path: Path, header, sizes) -> list[int]:
    """The three axes of an NRRD that are space: those with a space direction (the others
    say ``none``), else those of kind ``domain``/``space``; a 3-D file's three axes."""
    if len(sizes) == 3:
        return [0, 1, 2]
    if len(sizes) not in (4, 5):
        raise InvalidDataError(f"{path.name} is a {len(sizes)}-D NRRD, not a volume or a "
                               "sequence of volumes")
    if "space directions" in header:
        dirs = np.asarray(header["space directions"], dtype=float)
        axes = [a for a in range(len(sizes)) if np.all(np.isfinite(dirs[a]))]
    else:
        kinds = [str(k).lower() for k in header.get("kinds", [])]
        axes = [a for a, k in enumerate(kinds) if k in ("domain", "space")]
    if len(axes) != 3:
        raise InvalidDataError(f"{path.name} is a {len(sizes)}-D NRRD whose space directions "
                               "or kinds do not say which three axes are space")
    return axes


def _nrrd_frame_axis(header, axis: int, size: int) -> FrameAxis:
    """Name, coordinates and unit of a non-spatial NRRD axis, from its ``kinds``,
    ``labels``, ``axis mins``, ``spacings`` and ``units``."""
    def field(key):
        values = header.get(key)
        return None if values is None or len(values) <= axis else values[axis]

    kind = str(field("kinds") or "").lower()
    name = "channel" if kind in _NRRD_CHANNEL_KINDS else (kind if kind not in (
        "", "none", "???") else str(field("labels") or "frame"))
    values = None
    start, step = field("axis mins"), field("spacings")
    try:
        if step is not None and np.isfinite(float(step)):
            first = float(start) if start is not None and np.isfinite(float(start)) else 0.0
            values = tuple(first + i * float(step) for i in range(size))
    except (TypeError, ValueError):
        values = None
    unit = str(field("units") or "")
    return FrameAxis(name, size, values, "" if unit in ("none", "???") else unit)


#: NRRD ``space`` names of the two patient spaces (their short forms included)
_NRRD_SPACES = {"left-posterior-superior": "LPS", "lps": "LPS",
                "right-anterior-superior": "RAS", "ras": "RAS"}


#: a printf pattern of slice file names: one integer conversion, at most two digits of
#: width and precision (wider would only build huge names: "%0999999999d" is 1 GB a name)
_NAME_PATTERN = re.compile(r"^(?:[^%]|%%)*%[-+ #0]*(\d{0,2})(?:\.(\d{0,2}))?[diuoxX]"
                           r"(?:[^%]|%%)*$")
#: longest slice file name built from a pattern
MAX_NAME = 4096
#: most slice files one header may name: ten times the slices of the tallest micro-CT
#: stacks, and few enough that their names take a few MB (a header announcing 2*10^7 files
#: grew to 1.4 GB building their names)
MAX_SLICE_FILES = 65536


def _check_slice_count(path: Path, count: int) -> None:
    if count > MAX_SLICE_FILES:
        raise DataSizeError(f"{path.name} names {count:,} slice files; splineviz reads at most "
                            f"{MAX_SLICE_FILES:,} (one file per slice)")


def _pattern_names(path: Path, parts: list[str], expected: int) -> list[str]:
    """Slice file names of ``<printf pattern> <min> <max> <step>``: the pattern and the count
    are checked before any name is built (a header can ask for 10^9 names)."""
    if len(parts) < 4:
        raise CorruptFileError(f"{path.name} has a malformed multi-file data file entry")
    pattern = parts[0]
    if len(pattern) > MAX_NAME or _NAME_PATTERN.match(pattern) is None:
        raise CorruptFileError(f"{path.name} has an unusable file-name pattern {pattern[:60]!r} "
                               "(one integer conversion of at most 99 digits)")
    try:
        lo, hi, step = int(parts[1]), int(parts[2]), int(parts[3])
    except ValueError:
        raise CorruptFileError(f"{path.name} has a malformed file-name range "
                               f"{' '.join(parts[1:4])[:60]!r}") from None
    if step == 0 or (hi - lo) * step < 0:
        raise CorruptFileError(f"{path.name} has the empty file-name range {lo} to {hi} by "
                               f"{step}")
    count = len(range(lo, hi + (1 if step > 0 else -1), step))  # O(1), no list
    _check_slice_count(path, max(count, expected))
    if count != expected:
        raise DataSizeError(f"{path.name} lists {count:,} slice files for {expected} slices")
    return [pattern % i for i in range(lo, hi + (1 if step > 0 else -1), step)]


def _listed_names(path: Path, marker: bytes) -> list[str]:
    """File names one per line after the line matching ``marker`` (the LIST forms)."""
    with open_regular(path) as fh:
        text = fh.read(MAX_HEADER_BYTES + 1)
    if len(text) > MAX_HEADER_BYTES:
        raise CorruptFileError(f"{path.name} is a header of more than {MAX_HEADER_BYTES:,} "
                               "bytes")
    after = re.split(marker, text, maxsplit=1, flags=re.M | re.I)
    if len(after) != 2:
        return []
    _check_slice_count(path, after[1].count(b"\n"))  # lines, before any name is decoded
    return [ln.strip() for ln in after[1].decode("latin-1").splitlines() if ln.strip()]


#: largest detached header read whole (its LIST of slice files included)
MAX_HEADER_BYTES = 16 * 2**20


def _nrrd_file_list(path: Path, datafile: str, expected: int) -> list[str]:
    """File names of a multi-file NRRD: ``<printf pattern> <min> <max> <step> [<subdim>]`` or
    ``LIST [<subdim>]`` followed by one name per line (NRRD0004 "data file")."""
    parts = datafile.split()
    if parts[0].upper() == "LIST":
        names = _listed_names(path, rb"^data ?file:[^\n]*\n")
        subdim = parts[1] if len(parts) > 1 else None
    else:
        names = _pattern_names(path, parts, expected)
        subdim = parts[4] if len(parts) > 4 else None
    if subdim is not None and subdim != "2":
        raise FileFormatError(f"{path.name} splits its data into {subdim}-D files; only "
                              "one slice per file is supported")
    return names


def _read_nrrd_multifile(path: Path, header, datafile: str, sizes) -> np.ndarray:
    """One 2-D slice per file, each read by pynrrd's own payload decoder (raw, gzip, ...)."""
    import nrrd

    names = _nrrd_file_list(path, datafile, sizes[2])
    if len(names) != sizes[2]:
        raise DataSizeError(f"{path.name} lists {len(names)} slice files for {sizes[2]} slices")
    out = None
    for k, name in enumerate(names):
        slice_path = regular_input(confined(name, path, what="slice file"))
        h = {key: val for key, val in header.items()
             if key in ("type", "encoding", "endian", "line skip", "byte skip", "lineskip",
                        "byteskip")}
        # absolute: pynrrd joins a relative data file with the header's folder once more
        h.update(dimension=2, sizes=np.asarray(sizes[:2]),
                 **{"data file": str(slice_path.absolute())})
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sl = nrrd.read_data(h, None, str(path), index_order="F")
        except (nrrd.NRRDError, ValueError, EOFError, OSError, zlib.error, KeyError,
            TypeError, IndexError) as exc:
            raise CorruptFileError(f"slice file {name} of {path.name} is damaged or "
                                   f"truncated: {exc}") from None
        if out is None:
            out = np.empty((sizes[0], sizes[1], sizes[2]), dtype=sl.dtype)
        out[:, :, k] = sl.reshape(sizes[0], sizes[1], order="F") if sl.ndim != 2 else sl
    return out


def _nrrd_mapped(path: Path, header, datafile: str, sizes) -> MappedArray | None:
    """The samples of a raw-encoded 3-D NRRD too large to render in one piece
    (:func:`~splineviz.io.mapped.renders_in_pieces`), mapped where they lie in the file, or
    None for any other NRRD (compressed, text, line skips: pynrrd reads those whole)."""
    import nrrd

    if str(header.get("encoding", "")).lower() != "raw" or \
            any(k in header for k in ("line skip", "lineskip")):
        return None
    dtype = np.dtype(nrrd.reader._determine_datatype(header))
    if not renders_in_pieces(sizes, dtype):
        return None
    need = int(np.prod(sizes, dtype=object)) * dtype.itemsize
    skip = int(header.get("byte skip", header.get("byteskip", 0)))
    if datafile:
        target = regular_input(confined(datafile, path))
        size = target.stat().st_size
        offset = size - need if skip == -1 else skip
    else:  # attached: the samples follow the blank line that ends the header
        if skip:
            return None
        target = path
        size = target.stat().st_size
        end = _head(path, 2**20).find(b"\n\n")
        if end < 0:
            return None
        offset = end + 2
    if offset < 0 or offset + need != size:
        return None  # pynrrd reads it, or says what is wrong with it
    return MappedArray(target, offset, dtype, sizes, "F")


def _read_nrrd_single(path: Path, datafile: str):
    import nrrd

    if datafile:
        regular_input(confined(datafile, path))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return nrrd.read(str(path), index_order="F")
    except FileNotFoundError as exc:
        raise DataFileNotFoundError(f"{path.name} refers to a missing data file: "
                                    f"{exc.filename}") from None
    except (nrrd.NRRDError, ValueError, EOFError, OSError, zlib.error, KeyError,
            TypeError, IndexError) as exc:
        raise CorruptFileError(f"{path.name} has a damaged or truncated payload: {exc}") from None


def _write_nrrd(path: Path, vol: Volume) -> None:
    import nrrd

    # one row per array axis: its world step (an oblique volume's direction kept)
    header = {"space dimension": 3,
              "space directions": (vol.direction * np.asarray(vol.spacing)[None, :]).T,
              "space origin": np.asarray(vol.origin), "kinds": ["domain"] * 3,
              "encoding": "gzip"}
    with atomic_output(path) as tmp:
        nrrd.write(str(tmp), np.asarray(vol.data), header, index_order="F")


def _write_vti(path: Path, vol: Volume) -> None:
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    image = vtkImageData()
    image.SetDimensions(*vol.shape)
    image.SetSpacing(*vol.spacing)
    image.SetOrigin(*vol.origin)
    if not vol.axis_aligned:
        image.SetDirectionMatrix(*np.asarray(vol.direction, dtype=float).ravel())
    flat = np.ascontiguousarray(np.asarray(vol.data).ravel(order="F"))  # x fastest
    arr = numpy_to_vtk(flat, deep=True)
    arr.SetName("scalars")
    image.GetPointData().SetScalars(arr)
    with atomic_output(path) as tmp:
        writer = vtkXMLImageDataWriter()
        writer.SetFileName(str(tmp))
        writer.SetInputData(image)
        writer.SetCompressorTypeToZLib()
        writer.SetDataModeToAppended()
        with _vtk.captured_vtk_output() as out:
            ok = writer.Write()
        err = _vtk.first_vtk_error(out[0], generic="the writer failed")
        if not ok or err:
            from splineviz.io.errors import WriteError

            raise WriteError(f"cannot write {path.name}: {err or 'the writer failed'}")


# ---------------------------------------------------------------------------- MRC
def _mrc_axes(header) -> tuple[int, int, int]:
    """Array axis (of mrcfile's ``data[section, row, column]``) holding world x, y, z.

    MAPC/MAPR/MAPS say which world axis (1=x, 2=y, 3=z) runs along columns, rows and
    sections (MRC2014 words 17-19)."""
    crs = (int(header.mapc), int(header.mapr), int(header.maps))
    if sorted(crs) != [1, 2, 3]:
        raise CorruptFileError(f"MAPC/MAPR/MAPS {crs} are not a permutation of 1, 2, 3")
    array_axis_of_crs = (2, 1, 0)  # column -> last array axis, section -> first
    return tuple(array_axis_of_crs[crs.index(w + 1)] for w in range(3))


def _read_mrc(path: Path) -> VolumeData:
    """MRC/CCP4 maps with mrcfile: axes permuted to x, y, z by MAPC/MAPR/MAPS; voxel size
    from the cell (CELLA / MX,MY,MZ); origin from the ORIGIN field, or where that is zero from
    the start indices NCSTART/NRSTART/NSSTART times the voxel size (the CCP4 convention)."""
    import mrcfile

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with mrcfile.open(str(path), mode="r", permissive=False, header_only=True) as m:
                h = m.header
                dims = (int(h.nx), int(h.ny), int(h.nz))
                mode = int(h.mode)
    except (ValueError, OSError, EOFError) as exc:
        raise CorruptFileError(f"{path.name} has an invalid MRC header: {exc}") from None
    if any(n < 1 for n in dims):
        raise InvalidDataError(f"{path.name} announces an empty map of {dims} samples")
    itemsize = {0: 1, 1: 2, 2: 4, 3: 4, 4: 8, 6: 2, 12: 2}.get(mode, 4)
    check_volume_size(dims, itemsize, path.name)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with mrcfile.mmap(str(path), mode="r", permissive=False) as m:
                h = m.header
                if m.data is None or m.data.ndim != 3:
                    raise InvalidDataError(f"{path.name} does not hold a 3-D map")
                axes = _mrc_axes(h)
                if renders_in_pieces(dims, m.data.dtype):  # read brick by brick, mapped
                    data = None
                    source = AxisSource(MappedArray(path, 1024 + int(h.nsymbt), m.data.dtype,
                                                    m.data.shape, "C"), axes)
                else:  # copied out of the mapping in (x, y, z) order and the file's type
                    data = np.array(m.data.transpose(axes))
                vs = m.voxel_size
                spacing = (float(vs.x), float(vs.y), float(vs.z))
                org = np.array([float(h.origin.x), float(h.origin.y), float(h.origin.z)])
                start_crs = (int(h.nxstart), int(h.nystart), int(h.nzstart))
                crs = (int(h.mapc), int(h.mapr), int(h.maps))
    except (ValueError, OSError, EOFError) as exc:
        raise CorruptFileError(f"{path.name} has a damaged or truncated payload: {exc}") from None
    if not all(np.isfinite(s) and s > 0 for s in spacing):
        spacing = (1.0, 1.0, 1.0)  # CELLA 0 is common in maps from image processing tools
    if not np.any(org):
        start_xyz = [start_crs[crs.index(w + 1)] for w in range(3)]
        org = np.asarray(start_xyz, float) * np.asarray(spacing)
    # MRC/CCP4 cell dimensions are in Ångström (the format's definition)
    meta = {"axis_order": "".join("xyz"[c - 1] for c in crs), "length_unit": "Å"}
    if data is None:
        data = lazy_array(source)
        meta.update(levels=(), source=source)
    return VolumeData(data, spacing, tuple(float(o) for o in org), "mrc", meta)


# ---------------------------------------------------------------------------- NumPy, raw
def _read_npy(path: Path) -> VolumeData:
    try:
        arr = np.load(str(path), mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise CorruptFileError(f"{path.name} is not a valid .npy array: {exc}") from None
    if arr.ndim not in (3, 4, 5):
        raise InvalidDataError(f"{path.name} holds a {arr.ndim}-D array, not a volume")
    check_volume_size(arr.shape[:3], arr.dtype.itemsize, path.name)
    check_frame_count(arr.shape[3:], path.name)
    if arr.ndim == 3:
        if renders_in_pieces(arr.shape, arr.dtype):
            order = "F" if arr.flags.f_contiguous and not arr.flags.c_contiguous else "C"
            return _mapped_data(MappedArray(path, arr.offset, arr.dtype, arr.shape, order),
                                "npy")
        # stays mapped: Volume keeps a C-ordered array of a kept type as it is
        return VolumeData(np.asarray(arr), format="npy")
    # x, y, z first as in 3-D files; the trailing axes say nothing of what they are. The
    # file stays mapped: each frame is copied out when it is read.
    def read(index):
        return np.array(arr[(slice(None),) * 3 + tuple(int(i) for i in index)])

    frames = Frames(tuple(FrameAxis("frame", int(n)) for n in arr.shape[3:]), read)
    return VolumeData(read((0,) * (arr.ndim - 3)), format="npy", frames=frames)


def _write_npy(path: Path, vol: Volume) -> None:
    with atomic_output(path) as tmp:
        np.save(str(tmp), np.asarray(vol.data), allow_pickle=False)


def _read_raw(path: Path, *, dims=None, dtype=None, byteorder="little", offset=0) -> VolumeData:
    """Headerless samples: ``dims`` (nx, ny, nz), x fastest, of ``dtype`` with
    ``byteorder`` ("little"/"big"), after ``offset`` header bytes."""
    if dims is None or dtype is None:
        raise FileFormatError(f"{path.name} is raw data: give its dims and dtype")
    try:
        dims = tuple(int(n) for n in dims)
        dt = np.dtype(dtype)
    except (TypeError, ValueError):
        raise FileFormatError(f"invalid raw dims {dims!r} or dtype {dtype!r}") from None
    if len(dims) != 3:
        raise FileFormatError(f"raw dims must be three numbers, got {dims}")
    if byteorder not in ("little", "big"):
        raise FileFormatError(f"byteorder must be 'little' or 'big', got {byteorder!r}")
    if dt.kind not in "biuf" or dt.itemsize == 0:
        raise FileFormatError(f"raw dtype must be numeric, got {dt}")
    dt = dt.newbyteorder("<" if byteorder == "little" else ">")
    check_volume_size(dims, dt.itemsize, path.name)
    need = int(np.prod(dims, dtype=object)) * dt.itemsize
    have = path.stat().st_size - int(offset)
    if have != need:
        raise DataSizeError(
            f"{path.name} holds {have} bytes after the header but dims {dims} of {dt.name} "
            f"need {need}"
        )
    if need == 0:
        raise DataSizeError(f"{path.name} announces no samples (dims {dims})")
    if renders_in_pieces(dims, dt):
        return _mapped_data(MappedArray(path, offset, dt, dims, "F"), "raw")
    # mapped, not read: Volume copies it once into its (x, y, z) C order, in the file's type
    stored = np.memmap(str(path), dtype=dt, mode="r", offset=int(offset), shape=dims[::-1])
    return VolumeData(np.asarray(stored).transpose(2, 1, 0), format="raw")


def _mapped_data(source: MappedArray, fmt: str) -> VolumeData:
    """A volume too large to render in one piece (:func:`~splineviz.io.mapped.renders_in_pieces`),
    read lazily from its mapped file."""
    return VolumeData(lazy_array(source), format=fmt, meta={"levels": (), "source": source})


# ---------------------------------------------------------------------------- sniffing
def _head(path: Path, n: int) -> bytes:
    with open_regular(path) as fh:
        return fh.read(n)


register_format("vti", (".vti",), _read_vti, _write_vti, kind="volume",
                sniff=lambda h: b"<VTKFile" in h and b"ImageData" in h,
                description="VTK XML ImageData")
register_format("vtk", (".vtk",), _read_legacy_vtk, None, kind="volume",
                sniff=lambda h: h.startswith(b"# vtk DataFile"),
                description="legacy VTK structured points")
register_format("slc", (".slc",), _read_slc, None, kind="volume",
                sniff=lambda h: h.lstrip().startswith(b"11111"), description="SLC volume")
register_format("metaimage", (".mhd", ".mha"), _read_metaimage, None, kind="volume",
                sniff=lambda h: re.search(rb"^\s*(ObjectType|NDims)\s*=", h, re.M) is not None,
                description="MetaImage")
register_format("nrrd", (".nrrd", ".nhdr"), _read_nrrd, _write_nrrd, kind="volume",
                sniff=lambda h: h.startswith(b"NRRD000"), description="NRRD")
register_format("mrc", (".mrc", ".map", ".ccp4", ".mrcs"), _read_mrc, None, kind="volume",
                sniff=lambda h: len(h) >= 212 and h[208:211] == b"MAP",
                description="MRC/CCP4 map")
register_format("npy", (".npy",), _read_npy, _write_npy, kind="volume",
                sniff=lambda h: h.startswith(b"\x93NUMPY"), description="NumPy array")
register_format("raw", (".raw", ".bin", ".dat"), _read_raw, None, kind="volume",
                description="raw binary (needs dims and dtype)")

_RAW_OPTIONS = ("dims", "dtype", "byteorder", "offset")


def load_volume_data(path, *, format=None, dims=None, dtype=None, byteorder="little",
                     offset=0, allow_outside=False, channel=None, frame=0) -> VolumeData:
    """Read a volume file in its own sample type (see :func:`read_volume`).

    For a 4-D file, ``data`` is entry ``frame`` of the sequence that
    :func:`~splineviz.io.volume_data.select_frames` makes with ``channel``; ``frames``
    still reads any other, and ``meta["frame"]`` holds the file index read.
    """
    p = regular_input(path, allow_dir=True, allow_pattern=True)
    if dims is not None or dtype is not None:
        format = format or "raw"
    elif not p.exists():  # a pattern of numbered 2-D slices: scan/slice_*.tif, img_%03d.png
        format = format or "slices"
    fmt = find_format(p, "volume", name=format)
    with reader_errors(p.name, fmt.name), outside_allowed(allow_outside):
        if fmt.name == "raw":
            vd = fmt.reader(p, dims=dims, dtype=dtype, byteorder=byteorder, offset=offset)
        else:
            vd = fmt.reader(p)
    if not isinstance(vd, VolumeData):
        raise FileFormatError(f"the {fmt.name} reader returned {type(vd).__name__}, "
                              "not VolumeData")
    if vd.frames is not None:  # a plugin's reader too
        check_frame_count(vd.frames.shape, p.name)
    selection = select_frames(vd.frames, p.name, channel)
    if not 0 <= int(frame) < len(selection.indices):
        raise InvalidDataError(f"{p.name} has {len(selection.indices)} frame(s) along its "
                               f"{selection.axis.name} axis; frame {frame} is not one")
    index = selection.indices[int(frame)]
    if vd.frames is not None:
        if any(index):
            with reader_errors(p.name, fmt.name):
                vd.data = vd.frames.read(index)
        vd.meta["frame"] = index
    return vd


def read_volume(path, *, format=None, dims=None, dtype=None, byteorder="little", offset=0,
                spacing=None, origin=None, nonfinite="error", allow_outside=False,
                channel=None, complex="error", oblique="direction") -> Volume:
    """Read a volume file (or DICOM folder) into a :class:`~splineviz.Volume`.

    Parameters
    ----------
    path : path-like
        VTI, NRRD/NHDR, MHD/MHA, legacy .vtk, SLC, NIfTI, Analyze (.hdr/.img), MGH/MGZ, MINC1/2,
        PAR/REC, AFNI (BRIK/HEAD), MRC/MAP, DICOM folder, .npy, raw, TIFF, a folder or pattern
        of numbered 2-D TIFF or PNG slices (``scan/*.tif``, ``scan/img_%03d.png``), and the
        chunked and plugin formats of the registry. A 4-D file gives its first frame, with a
        :class:`~splineviz.core.errors.SplinevizWarning` that says how many there are
        (:func:`~splineviz.io.sequence.read_volume_sequence` reads them all).
    format : str, optional
        Force a registered format by name instead of guessing from suffix and content.
    dims, dtype, byteorder, offset
        Raw binaries: (nx, ny, nz) samples x fastest, NumPy dtype, "little"/"big", bytes of
        header to skip. Giving ``dims`` or ``dtype`` selects the raw reader.
    spacing, origin : (3,) float, optional
        Override the file's step along each array axis and the position of its first sample
        (raw files have none: default 1 and 0); a direction the file states is kept.
    nonfinite : {"error", "fill"}
        What to do with NaN/Inf samples: refuse the file (default), or replace them by the
        smallest finite sample (outside every isosurface above it) with a
        :class:`~splineviz.core.errors.SplinevizWarning`. A negative spacing, or a direction
        matrix that runs against a world axis, flips the axis (samples keep their world
        positions; :mod:`splineviz.io.geometry`), also with a warning; an oblique one keeps
        its rotation (see ``oblique``).
    allow_outside : bool
        Read data files that a header (MetaImage ``ElementDataFile``, NRRD ``data file``)
        names outside the header's folder; refused by default with an
        :class:`~splineviz.io.errors.OutsideFolderError`.
    channel : int, optional
        For a multi-channel file: the channel to read (see
        :func:`~splineviz.io.volume_data.select_frames`).
    complex : {"error", "magnitude"}
        Complex samples are refused (default) or replaced by their magnitude.
    oblique : {"direction", "resample", "error"}
        A grid rotated against the world axes (an oblique scan) keeps its rotation as the
        volume's ``direction`` (default: shown in place in world, :mod:`splineviz.core.
        frame`), is resampled trilinearly onto the axis-aligned grid covering it, with a
        warning (:func:`~splineviz.io.geometry.resample_axis_aligned`), or is refused. A
        sheared grid (axes not perpendicular: no rotation places it) is resampled unless
        refused.

    Returns
    -------
    Volume or ChunkedVolume
        ``data[i, j, k]`` at ``origin + direction @ ((i, j, k) * spacing)``, in the file's
        sample type
        where :class:`~splineviz.Volume` keeps it (else float32); chunked formats
        (OME-Zarr, Zarr, HDF5), and mapped ones too large to render in one piece, give a
        lazily read :class:`~splineviz.core.chunked.ChunkedVolume`.

    Raises
    ------
    SplinevizError
        A subclass from :mod:`splineviz.io.errors` with a one-sentence message.

    Examples
    --------
    >>> vol = read_volume("../shared/data/volumes/HeadMRVolume.mhd")  # doctest: +SKIP
    >>> vol.shape, vol.spacing  # doctest: +SKIP
    ((48, 62, 42), (4.0, 4.0, 4.0))
    """
    if nonfinite not in ("error", "fill"):
        raise ValueError(f"nonfinite must be 'error' or 'fill', got {nonfinite!r}")
    vd = load_volume_data(path, format=format, dims=dims, dtype=dtype, byteorder=byteorder,
                          offset=offset, allow_outside=allow_outside, channel=channel)
    name = Path(os.fspath(path)).name
    notice = frames_notice(name, select_frames(vd.frames, name, channel), channel)
    if notice:
        warnings.warn(notice, SplinevizWarning, stacklevel=2)
    if is_lazy(vd.data):  # OME-Zarr, Zarr, HDF5: a ChunkedVolume, read brick by brick
        if complex == "magnitude" and np.issubdtype(vd.data.dtype, np.complexfloating):
            raise InvalidDataError(f"{name} holds complex ({vd.data.dtype}) samples in chunks; "
                                   "their magnitude is taken only for volumes read whole")
        validate_volume_data(vd, name)
        return to_chunked_volume(vd, Path(os.fspath(path)).name, spacing=spacing,
                                 origin=origin, oblique=oblique)
    return to_volume(vd, name, spacing=spacing, origin=origin, nonfinite=nonfinite,
                     complex=complex, oblique=oblique)


def frames_notice(name: str, selection, channel=None) -> str | None:
    """One line saying which frame of a 4-D file is shown and how to choose, or None for a
    file of one frame (``selection``: :func:`~splineviz.io.volume_data.select_frames`)."""
    parts = []
    if len(selection.indices) > 1:
        parts.append(f"{len(selection.indices)} frames along its {selection.axis.name} axis "
                     "(the first is shown; read_volume_sequence reads them all)")
    if channel is None and selection.channels > 1:
        parts.append(f"{selection.channels} channels (channel 0 is shown; choose another "
                     "with channel=N or --channel N)")
    return f"{name} holds {' and '.join(parts)}" if parts else None


def to_volume(vd: VolumeData, name: str, *, spacing=None, origin=None,
              nonfinite="error", complex="error", oblique="direction") -> Volume:
    """Validate a :class:`VolumeData` and make it a :class:`~splineviz.Volume` (the second
    half of :func:`read_volume`, whose parameters these are).

    The samples keep the file's type where :class:`~splineviz.Volume` does (8- and 16-bit
    integers, float32; a memory-mapped array stays mapped when no flip or transpose is
    needed); the checks run slab by slab, so no full-size float copy is made."""
    if nonfinite not in ("error", "fill"):
        raise ValueError(f"nonfinite must be 'error' or 'fill', got {nonfinite!r}")
    if complex not in ("error", "magnitude"):
        raise ValueError(f"complex must be 'error' or 'magnitude', got {complex!r}")
    if oblique not in OBLIQUE_MODES:
        raise ValueError(f"oblique must be one of {', '.join(OBLIQUE_MODES)}, got {oblique!r}")
    raw = np.asarray(vd.data)
    if np.issubdtype(raw.dtype, np.complexfloating):
        if complex == "error":
            raise InvalidDataError(f"{name} holds complex ({raw.dtype}) samples; read it with "
                                   "complex='magnitude' to show their magnitude")
        raw = np.abs(raw)
        vd = replace(vd, data=raw)
    validate_volume_data(vd, name)
    try:
        sp = as_float_triplet(vd.spacing if spacing is None else spacing, "spacing")
        og = as_float_triplet(vd.origin if origin is None else origin, "origin")
    except ValueError as exc:
        raise InvalidDataError(f"{name} has unusable geometry: {exc}") from None
    if not all(s != 0 for s in sp):
        raise InvalidDataError(f"{name} has unusable geometry: spacing must be finite and "
                               f"positive, got {sp}")
    orient = orientation(affine_from(sp, og, vd.direction), raw.shape, name, space=vd.space)
    check_oblique(orient, name, oblique)
    data = _checked_samples(raw, name, nonfinite)
    direction = None
    if orient.oblique and (oblique == "resample" or orient.sheared):
        data, sp, og = resample_axis_aligned(data, orient, name, fill=float(data.min()))
    else:
        warn_flips(orient, name, stacklevel=4)
        data, sp, og = orient.apply(data), orient.spacing, orient.origin
        direction = orient.volume_direction
    try:
        return Volume(data, spacing=sp, origin=og, direction=direction,
                      unit=vd.meta.get("length_unit", ""))
    except (VolumeError, ValueError) as exc:
        raise InvalidDataError(f"{name} has unusable geometry: {exc}") from None


def _checked_samples(raw: np.ndarray, name: str, nonfinite: str) -> np.ndarray:
    """``raw`` with its non-finite samples refused or filled (:func:`to_volume`); integer
    samples are returned as they are (only floats hold NaN or infinities).

    Parameters
    ----------
    raw : (n0, n1, n2) ndarray, real
    name : file name for the messages
    nonfinite : {"error", "fill"}

    Returns
    -------
    (n0, n1, n2) ndarray: ``raw`` itself, or a float32 copy (wider floats, or samples filled)
    """
    if raw.dtype.kind != "f":
        return raw
    beyond = count = 0
    lo = np.inf
    big = raw.dtype.itemsize > 4
    with np.errstate(invalid="ignore", over="ignore"):
        for slab in slabs(raw):
            finite = np.isfinite(slab)
            count += int(slab.size - np.count_nonzero(finite))
            if big:
                # counted before the float32 cast, which would turn these into infinities
                # and the message into a false "infinite samples"
                beyond += int(np.count_nonzero(np.abs(slab) > np.finfo(np.float32).max))
            if finite.any():
                lo = min(lo, float(slab[finite].min()))
    if beyond:
        raise InvalidDataError(
            f"{name} has {beyond} finite samples beyond the float32 range "
            f"(magnitude above {np.finfo(np.float32).max:.3g}) that splineviz computes in; "
            "rescale the data")
    if count == raw.size:
        raise InvalidDataError(f"{name} has no finite samples (all {count:,} are NaN or "
                               "infinite), so there is nothing to show")
    if count and nonfinite == "error":
        raise InvalidDataError(f"{name} has {count} NaN or infinite samples "
                               "(read with nonfinite='fill' to replace them)")
    if not count:
        return raw
    fill = np.float32(lo)
    data = np.asarray(raw, dtype=np.float32)
    if data is raw or not data.flags.writeable:
        data = data.copy()
    for slab in slabs(data):
        slab[~np.isfinite(slab)] = fill
    warnings.warn(f"{name}: {count} NaN or infinite samples were replaced by {float(fill):g}, "
                  "the smallest finite sample", SplinevizWarning, stacklevel=4)
    return data


def validate_volume_data(vd: VolumeData, name: str) -> None:
    """Shape and type checks common to all formats (thesis splines need cells on each axis)."""
    shape = tuple(vd.data.shape)
    if len(shape) != 3:
        raise InvalidDataError(f"{name} holds a {len(shape)}-D array, not a volume")
    if min(shape) < MIN_SAMPLES_PER_AXIS:
        raise InvalidDataError(
            f"{name} has {shape} samples; a spline volume needs at least "
            f"{MIN_SAMPLES_PER_AXIS} along each axis"
        )
    if np.issubdtype(vd.data.dtype, np.complexfloating):
        raise InvalidDataError(f"{name} holds complex ({vd.data.dtype}) samples; read it with "
                               "complex='magnitude' to show their magnitude")
    if not (np.issubdtype(vd.data.dtype, np.number) or vd.data.dtype == bool):
        raise InvalidDataError(f"{name} holds {vd.data.dtype} samples, not real numbers")


def write_volume(path, volume, *, format=None) -> Path:
    """Write a :class:`~splineviz.Volume` (or 3-D array) as VTI, NRRD or NPY, atomically.

    Returns
    -------
    Path
        The written file.
    """
    vol = volume if isinstance(volume, Volume) else Volume(volume)
    p = Path(os.fspath(path)).expanduser()
    fmt = find_format(p, "volume", mode="write", name=format)
    fmt.writer(p, vol)
    return p
