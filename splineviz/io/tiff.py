"""TIFF volumes and stacks of 2-D slices, read with tifffile (PNG slices with Pillow).

A TIFF volume is the first series of the file as tifffile sees it: a multi-page stack, a
BigTIFF, an ImageJ hyperstack or an OME-TIFF; stored z, y, x, it becomes ``data[i, j, k]``
with i along x. Spacing comes from the file's metadata: ImageJ's ``spacing`` for z and the
XResolution/YResolution tags (pixels per unit) for x and y, or OME's PhysicalSizeX/Y/Z; a
plain TIFF has spacing 1. A folder or pattern (``scan/*.tif``, ``scan/img_%03d.png``) of
numbered 2-D TIFF or PNG slices is a stack in natural order (``s2`` before ``s10``).

A volume larger than :func:`lazy_threshold` is read lazily: a dask array whose bricks read
only the pages (TIFF tiles or strips through ``TiffFile.aszarr``) or slice files they meet,
turned into a :class:`~splineviz.core.chunked.ChunkedVolume` by
:func:`~splineviz.io.volumes.read_volume`.
"""

from __future__ import annotations

import glob
import os
import re
from pathlib import Path

import numpy as np

from splineviz.core.units import canonical_unit
from splineviz.io._util import (
    MIN_SAMPLES_PER_AXIS,
    PRINTF_NUMBER,
    check_volume_size,
    held_bytes,
)
from splineviz.io.chunked import AxisSource
from splineviz.io.errors import CorruptFileError, FileFormatError, InvalidDataError
from splineviz.io.mapped import LAZY_SHARE_ENV, lazy_threshold  # noqa: F401  (tests set it)
from splineviz.io.registry import register_format
from splineviz.io.volume_data import VolumeData

#: suffixes of the 2-D slices a folder or pattern may hold
SLICE_SUFFIXES = (".tif", ".tiff", ".png")
#: stored bytes per dask chunk of a lazily read stack: a preview or histogram pass holds a
#: few chunks per thread, each with its float32 copy
CHUNK_BYTES = 8 * 2**20

#: TIFF axes codes that can be the stack axis of a 3-D series (tifffile's: Z depth, Q/I
#: unnamed pages)
_STACK_AXES = "ZQIP"
_AXIS_NAMES = {"C": "channels", "T": "time points", "S": "colour samples", "Z": "slices",
               "E": "lambda steps", "R": "tiles", "H": "phases", "A": "angles",
               "V": "views", "L": "exposures", "M": "mosaic tiles"}
#: micrometres per unit of the names ImageJ and OME write
_UNITS_UM = {"nm": 1e-3, "nanometer": 1e-3, "um": 1.0, "µm": 1.0, "\u03bcm": 1.0,
             "micron": 1.0, "microns": 1.0, "micrometer": 1.0, "mm": 1e3, "millimeter": 1e3,
             "cm": 1e4, "m": 1e6, "meter": 1e6, "pixel": None, "px": None, "": None}


def _chunks(stored, dtype) -> tuple[int, int, int]:
    """Dask chunks (x, y, z) of a stack stored (z, y, x): whole pages, as many as fit in
    :data:`CHUNK_BYTES`, or bands of rows of one page when a page is larger."""
    nz, ny, nx = (int(n) for n in stored)
    row = nx * np.dtype(dtype).itemsize
    rows = min(ny, max(1, CHUNK_BYTES // row))
    pages = min(nz, max(1, CHUNK_BYTES // (row * ny))) if rows == ny else 1
    return nx, rows, pages


def natural_key(name: str):
    """Sort key that orders the numbers inside names by value (``s2`` before ``s10``)."""
    return [(0, int(t), "") if t.isdigit() else (1, 0, t.lower())
            for t in re.split(r"(\d+)", name) if t]


# ---------------------------------------------------------------------------- TIFF files
class TiffPages:
    """A picklable region reader of a TIFF series stored (z, y, x): opens the file in each
    process on first use and reads through ``TiffFile.aszarr`` only the pages, tiles or
    strips a region meets.

    Parameters
    ----------
    path : path-like
    series : int
    shape : (3,) int
        Stored shape (nz, ny, nx) after dropping the length-1 axes in ``index``.
    dtype : numpy dtype
    index : tuple
        Index into the series' full zarr array that selects the 3-D stack (``slice(None)``
        on kept axes, 0 on length-1 axes).
    """

    def __init__(self, path, series: int, shape, dtype, index):
        self.path = str(path)
        self.series = int(series)
        self.shape = tuple(int(n) for n in shape)
        self.dtype = np.dtype(dtype)
        self.index = tuple(index)
        self.ndim = 3
        self._array = None
        self._tif = None

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in ("_array", "_tif")}

    def __setstate__(self, state):
        self.__dict__.update(state, _array=None, _tif=None)

    def __del__(self):
        # the file stays open between region reads (parsing the page chain once); close
        # it with the reader, not at interpreter exit
        if getattr(self, "_tif", None) is not None:
            self._tif.close()

    def __getitem__(self, key) -> np.ndarray:
        import tifffile
        import zarr

        if self._array is None:
            self._tif = tifffile.TiffFile(self.path)
            self._array = zarr.open(self._tif.aszarr(series=self.series, level=0), mode="r")
        key = tuple(key) + (slice(None),) * (3 - len(tuple(key)))
        keys = iter(key)
        full = tuple(next(keys) if isinstance(i, slice) else i for i in self.index)
        return np.asarray(self._array[full])


def _resolution_step(page, tag: str) -> float | None:
    """Units per pixel from a resolution tag (pixels per unit), or None."""
    t = page.tags.get(tag)
    if t is None:
        return None
    try:
        num, den = t.value
        step = float(den) / float(num)
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return step if np.isfinite(step) and step > 0 else None


def _positive(value) -> float | None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if np.isfinite(v) and v > 0 else None


def _imagej_geometry(tif) -> tuple[tuple[float, float, float], str | None]:
    """(x, y, z) spacing and unit of an ImageJ file: x/y from the resolution tags (ImageJ
    writes pixels per unit there), z from ``spacing`` in its description."""
    md = tif.imagej_metadata or {}
    page = tif.pages.first
    sx = _resolution_step(page, "XResolution") or 1.0
    sy = _resolution_step(page, "YResolution") or sx
    sz = _positive(md.get("spacing")) or 1.0
    unit = md.get("unit")
    if isinstance(unit, str):
        unit = unit.encode("ascii", "backslashreplace").decode("unicode_escape")
    return (sx, sy, sz), unit or None


def _ome_geometry(tif, series: int) -> tuple[tuple[float, float, float], str | None]:
    """(x, y, z) spacing and unit of an OME-TIFF image from its Pixels PhysicalSize*
    attributes (OME's default unit: micrometre); sizes in other units are converted to the
    unit of PhysicalSizeX."""
    import tifffile

    try:
        ome = tifffile.xml2dict(tif.ome_metadata)["OME"]
        images = ome["Image"]
        image = images[series] if isinstance(images, list) else images
        pixels = image["Pixels"]
    except (KeyError, IndexError, TypeError, ValueError):
        return (1.0, 1.0, 1.0), None
    units = [str(pixels.get(f"PhysicalSize{a}Unit", "µm")) for a in "XYZ"]
    sizes = [_positive(pixels.get(f"PhysicalSize{a}")) for a in "XYZ"]
    scale = [_UNITS_UM.get(u) for u in units]
    out = []
    for size, s in zip(sizes, scale, strict=True):
        if size is not None and s is not None and scale[0] is not None:
            size = size * s / scale[0]
        out.append(size or 1.0)
    return tuple(out), units[0] if sizes[0] is not None else None


def _stack_index(axes: str, shape, name: str) -> tuple[tuple, tuple[int, int, int]]:
    """Index selecting the (z, y, x) stack of a series with ``axes``, and its shape; other
    axes must have length 1, else the file is refused naming them."""
    axes = axes.upper()
    if "S" in axes and shape[axes.index("S")] > 1:
        raise InvalidDataError(f"{name} holds colour (RGB) pictures, not a volume of "
                               "scalar samples")
    if "Y" not in axes or "X" not in axes:
        raise InvalidDataError(f"{name} has axes {axes}, without the Y and X of a picture")
    big = [n for n, a in enumerate(axes) if a not in "YX" and shape[n] > 1]
    extra = [n for n in big if axes[n] not in _STACK_AXES]
    if extra or len(big) > 1:
        what = ", ".join(f"{shape[n]} {_AXIS_NAMES.get(axes[n], axes[n])} ({axes[n]})"
                         for n in big)
        raise InvalidDataError(f"{name} holds {what}; splineviz reads one 3-D stack of one "
                               "channel and time point per file")
    if not big:
        raise InvalidDataError(f"{name} is a single 2-D picture, not a volume")
    stack = big
    z = stack[0]
    index = tuple(slice(None) if n in (z, axes.index("Y"), axes.index("X")) else 0
                  for n in range(len(axes)))
    if not axes.index("Y") < axes.index("X") or z > axes.index("Y"):
        raise InvalidDataError(f"{name} stores its axes as {axes}; splineviz reads stacks "
                               "stored slice by slice (z, y, x)")
    return index, (int(shape[z]), int(shape[axes.index("Y")]), int(shape[axes.index("X")]))


def _read_tiff(path: Path):
    """A multi-page TIFF, BigTIFF, ImageJ hyperstack or OME-TIFF (the first series)."""
    import dask.array as da
    import tifffile

    try:
        tif = tifffile.TiffFile(str(path))
    except tifffile.TiffFileError as exc:
        raise CorruptFileError(f"{path.name} is not a readable TIFF file: {exc}") from None
    with tif:
        if not tif.series:
            raise InvalidDataError(f"{path.name} holds no image series")
        series = tif.series[0]
        axes, shape, dtype = series.axes, tuple(series.shape), np.dtype(series.dtype)
        index, stored = _stack_index(axes, shape, path.name)
        if tif.is_ome:
            spacing, unit = _ome_geometry(tif, 0)
        elif tif.is_imagej:
            spacing, unit = _imagej_geometry(tif)
        else:
            spacing, unit = (1.0, 1.0, 1.0), None
        meta = {"axes": axes, "unit": unit, "length_unit": canonical_unit(unit),
                "bigtiff": bool(tif.is_bigtiff),
                "flavour": "ome" if tif.is_ome else "imagej" if tif.is_imagej else "tiff"}
        if min(stored) < MIN_SAMPLES_PER_AXIS:
            raise InvalidDataError(f"{path.name} has {stored[::-1]} samples; a spline volume "
                                   f"needs at least {MIN_SAMPLES_PER_AXIS} along each axis")
        if held_bytes(stored, dtype) <= lazy_threshold():
            check_volume_size(stored, dtype, path.name)
            try:
                data = np.asarray(series.asarray())[index]
            except (ValueError, NotImplementedError, RuntimeError) as exc:
                raise _decode_error(path.name, tif, exc) from None
            return VolumeData(data.reshape(stored).transpose(2, 1, 0), spacing, (0.0, 0.0, 0.0),
                              "tiff", meta)
    src = TiffPages(path, 0, stored, dtype, index)
    volume_src = AxisSource(src, (2, 1, 0))
    lazy = da.from_array(volume_src, chunks=_chunks(stored, dtype), asarray=False)
    return VolumeData(lazy, spacing, (0.0, 0.0, 0.0), "tiff",
                      {**meta, "levels": (), "source": volume_src})


def _decode_error(name: str, tif, exc) -> Exception:
    """A failed decode: the missing codec named when the compression needs imagecodecs."""
    comp = getattr(tif.pages.first, "compression", None)
    comp_name = getattr(comp, "name", str(comp))
    if "imagecodecs" in str(exc) or "codec" in str(exc).lower():
        return FileFormatError(f"{name} is compressed with {comp_name}; install the "
                               "imagecodecs package to decode it")
    return CorruptFileError(f"cannot decode the samples of {name}: {exc}")


# ---------------------------------------------------------------------------- slice stacks
def slice_files(path) -> list[Path]:
    """The 2-D slices of a folder or pattern, TIFF or PNG, in natural order.

    Parameters
    ----------
    path : path-like
        A folder, a glob pattern (``scan/slice_*.tif``) or a printf-style one
        (``scan/img_%03d.png``: every file whose number is written that way).

    Raises
    ------
    InvalidDataError
        No slice matches, or the folder mixes TIFF and PNG slices.
    """
    p = Path(os.fspath(path)).expanduser()
    if p.is_dir():
        files = [f for f in p.iterdir() if f.is_file() and f.suffix.lower() in SLICE_SUFFIXES
                 and not f.name.startswith(".")]
        where = f"folder {p.name}"
    else:
        if PRINTF_NUMBER.search(p.name):
            named = _printf_names(p)
        else:
            named = [Path(f) for f in glob.glob(str(p))]
        files = [f for f in named if f.is_file() and f.suffix.lower() in SLICE_SUFFIXES]
        where = f"pattern {p.name} in {p.parent}"
    if not files:
        raise InvalidDataError(f"{where} matches no TIFF or PNG slices")
    kinds = {f.suffix.lower() == ".png" for f in files}
    if len(kinds) > 1:
        raise InvalidDataError(f"{where} mixes TIFF and PNG slices; keep one kind per stack")
    return sorted(files, key=lambda f: natural_key(f.name))


def _printf_names(pattern: Path) -> list[Path]:
    """The files of ``pattern``'s folder whose names its printf-style number matches:
    ``%03d`` three digits or more (zero-padded), ``%d`` any."""
    parts = PRINTF_NUMBER.split(pattern.name)
    # split keeps the two groups of each number: (text, zero, width, text, ...)
    regex = re.escape(parts[0])
    for k in range(1, len(parts), 3):
        zero, width = parts[k], parts[k + 1]
        regex += rf"\d{{{int(width)},}}" if zero and width else r"\d+"
        regex += re.escape(parts[k + 2])
    folder = pattern.parent
    try:
        names = [e.name for e in os.scandir(folder)]
    except OSError:
        return []
    rx = re.compile(regex)
    return [folder / n for n in names if rx.fullmatch(n)]


def _read_picture(path: Path) -> np.ndarray:
    """One 2-D slice, (rows, columns), in its own sample type."""
    if path.suffix.lower() == ".png":
        from PIL import Image, UnidentifiedImageError

        try:
            with Image.open(path) as im:
                mode = im.mode
                arr = np.asarray(im) if mode in ("L", "I", "I;16", "I;16B", "F", "1") else None
        except (UnidentifiedImageError, OSError, ValueError) as exc:
            raise CorruptFileError(f"{path.name} is not a readable PNG: {exc}") from None
        if arr is None:
            raise InvalidDataError(f"{path.name} is a colour ({mode}) picture; slices must be "
                                   "greyscale")
    else:
        import tifffile

        try:
            arr = tifffile.imread(str(path), key=0)
        except (tifffile.TiffFileError, ValueError, OSError) as exc:
            raise CorruptFileError(f"{path.name} is not a readable TIFF: {exc}") from None
    arr = np.asarray(arr)
    if arr.ndim == 3 and arr.shape[-1] in (3, 4):
        raise InvalidDataError(f"{path.name} is a colour (RGB) picture; slices must be "
                               "greyscale")
    if arr.ndim != 2:
        raise InvalidDataError(f"{path.name} holds a {arr.ndim}-D array, not a 2-D slice")
    return arr


class SliceFiles:
    """A picklable region reader of a stack of 2-D slice files, stored (z, y, x): a region
    reads only the files of its slices.

    Parameters
    ----------
    files : sequence of path-like
        The slices in stack order.
    shape : (3,) int
        (number of files, rows, columns).
    dtype : numpy dtype
    """

    def __init__(self, files, shape, dtype):
        self.files = [str(f) for f in files]
        self.shape = tuple(int(n) for n in shape)
        self.dtype = np.dtype(dtype)
        self.ndim = 3

    def __getitem__(self, key) -> np.ndarray:
        key = tuple(key) + (slice(None),) * (3 - len(tuple(key)))
        zs = range(*key[0].indices(self.shape[0])) if isinstance(key[0], slice) else [key[0]]
        out = np.empty((len(zs),) + tuple(
            len(range(*k.indices(n))) for k, n in zip(key[1:], self.shape[1:], strict=True)),
            dtype=self.dtype)
        for n, z in enumerate(zs):
            out[n] = _checked_slice(Path(self.files[z]), self.shape[1:], self.dtype)[key[1:]]
        return out if isinstance(key[0], slice) else out[0]


def _checked_slice(path: Path, shape, dtype) -> np.ndarray:
    arr = _read_picture(path)
    if arr.shape != tuple(shape) or arr.dtype != dtype:
        raise InvalidDataError(f"slice {path.name} is {arr.shape[1]}x{arr.shape[0]} "
                               f"{arr.dtype}; the stack's first slice is "
                               f"{shape[1]}x{shape[0]} {np.dtype(dtype)}")
    return arr


def read_slices(path):
    """A folder or glob pattern of numbered 2-D TIFF or PNG slices as one volume.

    Parameters
    ----------
    path : path-like
        A folder, or a pattern such as ``scan/slice_*.tif``.

    Returns
    -------
    VolumeData
        ``data`` (columns, rows, slices); lazily read (a dask array) when larger than
        :func:`lazy_threshold`. Spacing from the first slice's ImageJ metadata, else 1.
    """
    import dask.array as da

    files = slice_files(path)
    name = Path(os.fspath(path)).name
    if len(files) < MIN_SAMPLES_PER_AXIS:
        raise InvalidDataError(f"{name} holds {len(files)} slice; a volume needs at least "
                               f"{MIN_SAMPLES_PER_AXIS}")
    first = _read_picture(files[0])
    stored = (len(files),) + tuple(first.shape)
    spacing = (1.0, 1.0, 1.0)
    unit = None
    if files[0].suffix.lower() != ".png":
        import tifffile

        with tifffile.TiffFile(str(files[0])) as tif:
            if tif.is_imagej:
                spacing, unit = _imagej_geometry(tif)
    meta = {"files": len(files), "unit": unit, "length_unit": canonical_unit(unit),
            "first": files[0].name}
    src = SliceFiles(files, stored, first.dtype)
    if held_bytes(stored, first.dtype) <= lazy_threshold():
        check_volume_size(stored, first.dtype, name)
        data = np.empty(stored, dtype=first.dtype)
        data[0] = first
        for z in range(1, len(files)):
            data[z] = _checked_slice(files[z], first.shape, first.dtype)
        return VolumeData(data.transpose(2, 1, 0), spacing, (0.0, 0.0, 0.0), "slices", meta)
    volume_src = AxisSource(src, (2, 1, 0))
    lazy = da.from_array(volume_src, chunks=_chunks(stored, first.dtype), asarray=False)
    return VolumeData(lazy, spacing, (0.0, 0.0, 0.0), "slices",
                      {**meta, "levels": (), "source": volume_src})


def _is_slice_folder(path: Path) -> bool:
    """A folder whose files are mostly TIFF or PNG pictures (at least two)."""
    try:
        files = [f for f in path.iterdir() if f.is_file() and not f.name.startswith(".")]
    except OSError:
        return False
    pics = sum(f.suffix.lower() in SLICE_SUFFIXES for f in files)
    return pics >= 2 and pics * 2 > len(files)


def _sniff_tiff(head: bytes) -> bool:
    """Classic TIFF (version 42) or BigTIFF (43) in either byte order."""
    return head[:4] in (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")


register_format("tiff", (".tif", ".tiff", ".btf", ".tf8", ".ome.tif", ".ome.tiff"), _read_tiff,
                None, kind="volume", sniff=_sniff_tiff,
                description="TIFF stack (multi-page, BigTIFF, ImageJ hyperstack, OME-TIFF)")
register_format("slices", (), read_slices, None, kind="volume", folder=True,
                sniff=_is_slice_folder,
                description="folder of numbered 2-D TIFF or PNG slices")
