"""Neuroimaging volume formats, read with nibabel: NIfTI-1/2 (single file or .hdr/.img pair),
Analyze 7.5 and SPM (.hdr/.img), MGH/MGZ (FreeSurfer), MINC1 and MINC2, PAR/REC (Philips)
and AFNI (BRIK/HEAD).

Values are nibabel's own (``dataobj`` with the file's scaling: MINC image-min/max, MGH and
NIfTI slope/intercept, PAR/REC per-slice scaling) and the geometry is nibabel's ``affine``,
which maps array indices to RAS+ world millimetres; :func:`~splineviz.io.volumes.to_volume`
makes it axis-aligned by :mod:`splineviz.io.geometry`'s rule. A 4-D (or 5-D) file gives its
first frame and the others on demand (:class:`~splineviz.io.volume_data.Frames`, one frame
read at a time), each axis named from the file's metadata where it says what the axis is.

Uncompressed NIfTI, Analyze and MGH samples are memory-mapped (nibabel's ``mmap``): read
whole, they are copied once, into the volume; a 3-D file too large to render in one piece
(:func:`~splineviz.io.mapped.renders_in_pieces`) opens as a chunked volume whose bricks read
their own box of the mapped file, scaled as nibabel scales it (:class:`ScaledArray`) and
turned into world order (:class:`~splineviz.io.mapped.OrientedArray`).
"""

from __future__ import annotations

import gzip
import zlib
from pathlib import Path

import numpy as np

from splineviz.io._util import check_volume_size
from splineviz.io.chunked import HDF5_SIGNATURE
from splineviz.io.errors import (
    CorruptFileError,
    DataFileNotFoundError,
    InvalidDataError,
)
from splineviz.io.registry import read_head, register_format
from splineviz.io.volume_data import FrameAxis, Frames, VolumeData, check_frame_count

#: the group every MINC2 file has at its root; HDF5 keeps root names near the start
MINC2_MARK = b"minc-2.0"
#: NetCDF classic and 64-bit-offset signatures (MINC1)
NETCDF_SIGNATURES = (b"CDF\x01", b"CDF\x02")


def sniff_minc(head: bytes) -> bool:
    """MINC1 (NetCDF) or MINC2 (HDF5 holding a ``minc-2.0`` group) from the first bytes."""
    return head[:4] in NETCDF_SIGNATURES or is_minc2(head)


def is_minc2(head: bytes) -> bool:
    """Whether an HDF5 file's first bytes name the MINC2 root group (read as MINC2, not as
    a bare HDF5 dataset)."""
    return head.startswith(HDF5_SIGNATURE) and MINC2_MARK in head


def _gunzip_head(head: bytes, n: int) -> bytes:
    if head[:2] != b"\x1f\x8b":
        return head
    try:
        return zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(head, n)
    except zlib.error:
        return b""


def sniff_nifti(head: bytes) -> bool:
    """NIfTI-1: sizeof_hdr 348 and magic ``n+1``/``ni1`` at byte 344; NIfTI-2: sizeof_hdr 540
    and magic ``n+2``/``ni2`` at byte 4 (either byte order; gzip streams are peeked into)."""
    head = _gunzip_head(head, 352)
    if len(head) < 8:
        return False
    size = {int.from_bytes(head[:4], "little"), int.from_bytes(head[:4], "big")}
    if 540 in size and head[4:7] in (b"n+2", b"ni2"):
        return True
    return 348 in size and len(head) >= 348 and head[344:347] in (b"n+1", b"ni1")


def sniff_mgh(head: bytes) -> bool:
    """MGH version 1: a big-endian int32 1, then three positive int32 dimensions (MGZ is
    the same, gzipped)."""
    head = _gunzip_head(head, 16)
    if len(head) < 16 or head[:4] != b"\x00\x00\x00\x01":
        return False
    dims = np.frombuffer(head[4:16], ">i4")
    return bool(np.all(dims > 0))


def _nibabel_errors():
    import nibabel as nib
    from nibabel.brikhead import AFNIHeaderError
    from nibabel.filebasedimages import ImageFileError
    from nibabel.minc1 import MincError
    from nibabel.parrec import PARRECError
    from nibabel.spatialimages import HeaderDataError, ImageDataError

    return (ImageFileError, HeaderDataError, ImageDataError, AFNIHeaderError, MincError,
            PARRECError, nib.wrapstruct.WrapStructError, ValueError, KeyError, IndexError,
            TypeError, EOFError, zlib.error)


def _load(path: Path, description: str):
    """``nibabel.load``; a file recognised by its content under a name nibabel does not know
    (nibabel chooses the class by the file name) is opened with the class its content
    names."""
    import nibabel as nib

    try:
        try:
            return nib.load(str(path))
        except nib.filebasedimages.ImageFileError:
            cls = _class_by_content(read_head(path))
            if cls is None:
                raise
            if cls in (nib.Minc1Image, nib.Minc2Image):
                return cls.from_file_map({"image": nib.FileHolder(filename=str(path))})
            raw = path.read_bytes()
            return cls.from_bytes(gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw)
    except FileNotFoundError as exc:
        missing = Path(exc.filename).name if exc.filename else "its data file"
        raise DataFileNotFoundError(f"{path.name} needs {missing}, which is missing") from None
    except _nibabel_errors() as exc:
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CorruptFileError(f"{path.name} is not a readable {description} file: "
                               f"{detail}") from None


def _class_by_content(head: bytes):
    """The nibabel image class of a single-file format recognised by its first bytes."""
    import nibabel as nib

    if sniff_nifti(head):
        plain = _gunzip_head(head, 8)
        two = 540 in (int.from_bytes(plain[:4], "little"), int.from_bytes(plain[:4], "big"))
        return nib.Nifti2Image if two else nib.Nifti1Image
    if head[:4] in NETCDF_SIGNATURES:
        return nib.Minc1Image
    if is_minc2(head):
        return nib.Minc2Image
    if sniff_mgh(head):
        return nib.MGHImage
    return None


def _reopen_by_name(img) -> None:
    """nibabel's PAR/REC proxy keeps the REC file open for the life of the image (and
    leaks it); given the file's name instead it opens the file for each frame it reads and
    closes it again."""
    proxy = img.dataobj
    handle = getattr(proxy, "file_like", None)
    holder = getattr(img, "file_map", {}).get("image")
    if hasattr(handle, "close") and holder is not None and holder.filename is not None:
        handle.close()
        proxy.file_like = holder.filename


def _spatial_axes(img) -> tuple[int, int, int]:
    """Array axes that the affine's i, j, k index: the first three, but MINC's own order for
    files that keep time first (``time, zspace, yspace, xspace``)."""
    proxy = img.dataobj
    minc = getattr(proxy, "minc_file", None)
    if minc is not None:
        names = list(minc._dim_names)
        spatial = [names.index(n) for n in minc._spatial_dims]
        if len(spatial) == 3:
            return tuple(spatial)
    return (0, 1, 2)


def _length_unit(img) -> str:
    """The unit of the affine's world coordinates: NIfTI's ``xyzt_units`` ("unknown" says
    none); MGH files are millimetres by definition (FreeSurfer); other formats do not say."""
    from splineviz.core.units import canonical_unit

    kind = type(img).__name__
    if kind.startswith("Nifti"):
        return canonical_unit(img.header.get_xyzt_units()[0])
    if kind.startswith("MGH"):
        return "mm"
    return ""


def _frame_axes(img, extra: list[int]) -> tuple[FrameAxis, ...]:
    """Name, size and coordinates of the non-spatial axes, from the file's metadata."""
    shape = img.shape
    header = img.header
    kind = type(img).__name__
    axes = []
    for n, ax in enumerate(extra):
        size = int(shape[ax])
        name, values, unit = "frame", None, ""
        if kind.startswith("Nifti") and ax == 3:
            t_unit = header.get_xyzt_units()[1]
            if t_unit in ("sec", "msec", "usec"):
                step = float(header.get_zooms()[3])
                start = float(header["toffset"])
                name, unit = "time", {"sec": "s", "msec": "ms", "usec": "us"}[t_unit]
                values = tuple(start + i * step for i in range(size))
        elif kind.startswith("Nifti") and ax == 4:
            name = "channel"  # NIfTI's fifth dimension holds vector components
        elif kind.startswith("Minc"):
            minc = img.dataobj.minc_file
            name = str(minc._dim_names[ax])
            var = minc._dims[ax]  # a MINC dimension variable: regular start and step
            start, step = getattr(var, "start", None), getattr(var, "step", None)
            if name == "time" and start is not None and step is not None:
                values = tuple(float(start) + i * float(step) for i in range(size))
                raw_unit = getattr(var, "units", b"")
                unit = raw_unit.decode("latin-1") if isinstance(raw_unit, bytes) else \
                    str(raw_unit)
        elif kind == "MGHImage":
            tr = float(header["tr"])
            if tr > 0:
                name, unit = "time", "ms"
                values = tuple(i * tr for i in range(size))
        elif kind == "AFNIImage":
            nums = header.info.get("TAXIS_NUMS")
            floats = header.info.get("TAXIS_FLOATS")
            if nums and floats and len(floats) > 1:
                # TAXIS_NUMS[2]: 77001 ms, 77002 s, 77003 Hz (AFNI's units codes)
                unit = {77001: "ms", 77002: "s", 77003: "Hz"}.get(int(nums[2]), "")
                name = "time"
                values = tuple(float(floats[0]) + i * float(floats[1]) for i in range(size))
            else:
                name = "sub-brick"
        elif kind == "PARRECImage" and n == 0:
            labels = header.get_volume_labels()
            varying = [k for k, v in labels.items() if len(np.unique(v)) > 1]
            name = " and ".join(varying) if varying else "frame"
        axes.append(FrameAxis(name, size, values, unit))
    return tuple(axes)


def _read_nibabel(path: Path, description: str, fmt: str) -> VolumeData:
    import nibabel as nib

    img = _load(path, description)
    if not isinstance(img, nib.spatialimages.SpatialImage) or getattr(img, "affine",
                                                                        None) is None:
        raise InvalidDataError(f"{path.name} is a {type(img).__name__}, not a volume with a "
                               "voxel-to-world affine")
    _reopen_by_name(img)
    for holder in getattr(img, "file_map", {}).values():
        # a header-only pair (.hdr without its .img): nibabel loads lazily and would fail
        # only when the samples are read
        if holder.filename is not None and not Path(holder.filename).exists():
            raise DataFileNotFoundError(f"{path.name} needs {Path(holder.filename).name}, "
                                        "which is missing")
    shape = tuple(int(n) for n in img.shape)
    if len(shape) < 3:
        raise InvalidDataError(f"{path.name} is a {len(shape)}-D image, not a volume")
    spatial = _spatial_axes(img)
    extra = [a for a in range(len(shape)) if a not in spatial and shape[a] > 1]
    single = [a for a in range(len(shape)) if a not in spatial and shape[a] == 1]
    if len(extra) > 2:
        raise InvalidDataError(f"{path.name} has shape {shape}: more than two non-spatial "
                               "axes (a volume sequence has time and at most channels)")
    check_frame_count([shape[a] for a in extra], path.name)
    affine = np.asarray(img.affine, dtype=float)
    m = affine[:3, :3]
    steps = np.linalg.norm(m, axis=0)
    if not np.all(np.isfinite(affine)) or not np.all(steps > 0):
        raise InvalidDataError(f"{path.name} has a degenerate voxel-to-world affine "
                               f"(voxel sizes {', '.join(f'{s:g}' for s in steps)})")
    proxy = img.dataobj
    if not extra:
        mapped = _mapped(img, path, shape, spatial, affine, fmt)
        if mapped is not None:
            return mapped
    # the budget is checked for the type nibabel's values come in, before any is read
    check_volume_size([shape[a] for a in spatial], _value_dtype(img), path.name)

    def read(index: tuple[int, ...]) -> np.ndarray:
        key: list = [slice(None)] * len(shape)
        for a in single:
            key[a] = 0
        for a, i in zip(extra, index, strict=True):
            key[a] = int(i)
        try:
            block = np.asanyarray(proxy[tuple(key)])
        except (OSError, *_nibabel_errors()) as exc:
            raise CorruptFileError(f"{path.name} has a damaged or truncated payload: "
                                   f"{exc}") from None
        kept = [a for a in range(len(shape)) if isinstance(key[a], slice)]
        # the kept axes are the spatial ones, in file order: put them in i, j, k order
        return np.transpose(block, [kept.index(a) for a in spatial])

    frames = None
    if extra:
        frames = Frames(_frame_axes(img, extra), read)
    data = read((0,) * len(extra))
    direction = m / steps[None, :]
    # spatial_axes: the array axes of the file that i, j, k are (MINC may keep time first)
    meta = {"class": type(img).__name__, "spatial_axes": spatial,
            "length_unit": _length_unit(img)}
    return VolumeData(data, tuple(float(s) for s in steps),
                      tuple(float(v) for v in affine[:3, 3]), fmt, meta,
                      None if np.array_equal(direction, np.eye(3)) else direction, "RAS",
                      frames)


def _plain_array_proxy(img):
    """nibabel's ArrayProxy of an image whose samples lie uncompressed in one file, in
    Fortran order (NIfTI, Analyze and MGH files that are not gzipped), else None."""
    from nibabel.arrayproxy import ArrayProxy
    from nibabel.openers import ImageOpener

    proxy = img.dataobj
    if type(proxy) is not ArrayProxy or proxy.order != "F":
        return None
    holder = getattr(img, "file_map", {}).get("image")
    name = getattr(holder, "filename", None)
    if name is None or Path(name).suffix.lower() in ImageOpener.compress_ext_map:
        return None
    return proxy


def _value_dtype(img) -> np.dtype:
    """The type of nibabel's values (``dataobj[...]``): the stored type when no scaling
    applies, the float type nibabel scales in when one does (float64 for the proxies
    other than ArrayProxy: MINC, PAR/REC, AFNI)."""
    from nibabel.arrayproxy import ArrayProxy
    from nibabel.volumeutils import apply_read_scaling

    proxy = img.dataobj
    if type(proxy) is not ArrayProxy:
        return np.dtype(np.float64)
    stored = np.zeros(1, np.dtype(img.get_data_dtype()))
    return np.asarray(apply_read_scaling(stored, np.asanyarray(proxy.slope),
                                         np.asanyarray(proxy.inter))).dtype


class ScaledArray:
    """Region reads of stored samples with nibabel's read scaling applied
    (``stored * slope + inter``, exactly as ``ArrayProxy`` computes it), as float32, the
    type splineviz computes in.

    Parameters
    ----------
    source : region reader (:class:`~splineviz.io.mapped.MappedArray`)
    slope, inter : NumPy scalars
        The proxy's scale factors, in their own types (they choose nibabel's float type).
    """

    def __init__(self, source, slope, inter):
        self.source = source
        self.slope = np.asanyarray(slope)
        self.inter = np.asanyarray(inter)
        self.shape = tuple(source.shape)
        self.dtype = np.dtype(np.float32)
        self.ndim = 3

    def __dask_tokenize__(self):
        from dask.base import tokenize

        return ("scaled", tokenize(self.source), float(self.slope), float(self.inter))

    def __getitem__(self, key) -> np.ndarray:
        """The values of ``key`` (a NumPy index), float32."""
        from nibabel.volumeutils import apply_read_scaling

        # ArrayProxy._get_scaled: the intercept takes the slope's type where it can
        inter = self.inter.astype(self.slope.dtype) if np.can_cast(
            self.inter, self.slope.dtype) else self.inter
        return np.asarray(apply_read_scaling(self.source[key], self.slope, inter),
                          dtype=np.float32)


def _mapped(img, path: Path, shape, spatial, affine, fmt: str) -> VolumeData | None:
    """A 3-D volume too large to render in one piece
    (:func:`~splineviz.io.mapped.renders_in_pieces`) whose samples lie uncompressed in one
    file: read brick by brick from the mapped file (scaled as nibabel scales them, turned
    into world order as :func:`~splineviz.io.volumes.to_volume` would; an oblique grid's
    rotation kept as the direction), or None for the eager path (smaller volumes,
    compressed files, other proxies, sheared grids, which are resampled)."""
    from splineviz.io.geometry import orientation, warn_flips
    from splineviz.io.mapped import (
        MappedArray,
        OrientedArray,
        lazy_array,
        renders_in_pieces,
    )

    proxy = _plain_array_proxy(img)
    if proxy is None or tuple(spatial) != (0, 1, 2):
        return None
    dims = tuple(shape[:3])
    if not renders_in_pieces(dims, _value_dtype(img)):
        return None
    orient = orientation(affine, dims, path.name, space="RAS")
    if orient.sheared:
        return None  # read whole: resampled by to_volume
    image = Path(img.file_map["image"].filename)
    stored = np.dtype(proxy.dtype)
    if image.stat().st_size < int(proxy.offset) + int(np.prod(dims, dtype=object)) * \
            stored.itemsize:
        raise CorruptFileError(f"{path.name} announces {dims} samples of {stored.name} but "
                               f"{image.name} is shorter")
    source = MappedArray(image, int(proxy.offset), stored, dims, "F")
    if (proxy.slope, proxy.inter) != (1, 0):
        source = ScaledArray(source, proxy.slope, proxy.inter)
    if not orient.identity:
        source = OrientedArray(source, orient.perm, orient.flips)
        warn_flips(orient, path.name, stacklevel=7)
    meta = {"class": type(img).__name__, "spatial_axes": tuple(spatial), "levels": (),
            "source": source, "affine": affine.tolist()}
    return VolumeData(lazy_array(source), orient.spacing, orient.origin, fmt, meta,
                      orient.volume_direction, "RAS")


def _reader(description: str, fmt: str):
    def read(path: Path) -> VolumeData:
        return _read_nibabel(path, description, fmt)

    read.__doc__ = f"{description} through nibabel (see :mod:`splineviz.io.neuro`)."
    return read


register_format("nifti", (".nii", ".nii.gz"), _reader("NIfTI", "nifti"), None,
                kind="volume", sniff=sniff_nifti, description="NIfTI-1/2")
# .hdr/.img pairs: Analyze 7.5, SPM99/SPM2 or NIfTI pair, nibabel tells which from the header;
# no signature check, so that the .img half opens too
register_format("analyze", (".hdr", ".img", ".img.gz"), _reader("Analyze/NIfTI pair",
                                                                  "analyze"), None,
                kind="volume", description="Analyze 7.5 / SPM / NIfTI pair (.hdr + .img)")
register_format("mgh", (".mgz", ".mgh"), _reader("MGH/MGZ", "mgh"), None, kind="volume",
                sniff=sniff_mgh, description="FreeSurfer MGH/MGZ")
register_format("minc", (".mnc",), _reader("MINC", "minc"), None, kind="volume",
                sniff=sniff_minc, description="MINC1 (NetCDF) / MINC2 (HDF5)")
register_format("parrec", (".par", ".rec"), _reader("PAR/REC", "parrec"), None,
                kind="volume", description="Philips PAR/REC")
register_format("afni", (".head", ".brik", ".brik.gz"), _reader("AFNI BRIK/HEAD", "afni"),
                None, kind="volume", description="AFNI BRIK/HEAD")
