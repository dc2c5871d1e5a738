"""Chunked volume formats, read lazily: OME-Zarr (multiscale), Zarr arrays and HDF5 datasets.

Readers return a :class:`~splineviz.io.volume_data.VolumeData` whose ``data`` is a dask array
(nothing read but metadata) and whose ``meta`` holds the coarser levels and a *source* for
region reads (the zarr array or HDF5 dataset itself, which reads only the chunks a box
meets); :func:`splineviz.io.volumes.read_volume` turns it into a
:class:`~splineviz.core.chunked.ChunkedVolume`.

Axis order: OME-Zarr arrays follow their ``axes`` metadata (usually z, y, x; turned into
``data[i, j, k]`` with i along x) and their scale/translation transforms give spacing and
origin per level. Plain Zarr arrays and HDF5 datasets are taken as stored, first axis = x
(as ``.npy``), with ``spacing``/``origin`` attributes when present (HDF5 also
``element_size_um``, z, y, x as ImageJ writes it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from splineviz.core.units import canonical_unit
from splineviz.io.errors import CorruptFileError, InvalidDataError
from splineviz.io.registry import formats, register_format
from splineviz.io.volume_data import VolumeData

#: the first bytes of every HDF5 file (superblock signature at offset 0)
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


class AxisSource:
    """Region reads of an array in another axis order: ``source[slices]`` with slices in the
    volume's (x, y, z) order, read from ``array`` whose axes are ``perm`` of them.

    Parameters
    ----------
    array : object with ``shape``, ``dtype`` and ``__getitem__`` (zarr array, HDF5 reader)
    perm : (3,) int
        ``volume axis a`` = ``array axis perm[a]``.
    """

    def __init__(self, array, perm=(0, 1, 2)):
        self.array = array
        self.perm = tuple(int(p) for p in perm)
        self.shape = tuple(int(array.shape[p]) for p in self.perm)
        self.dtype = np.dtype(array.dtype)
        self.ndim = 3

    def __getitem__(self, key) -> np.ndarray:
        key = tuple(key) + (slice(None),) * (3 - len(tuple(key)))
        stored = [None] * 3
        for a, p in enumerate(self.perm):
            stored[p] = key[a]
        block = np.asarray(self.array[tuple(stored)])
        # stored axis p holds volume axis perm.index(p): move them into volume order
        return np.ascontiguousarray(np.transpose(block, self.perm))


class H5Dataset:
    """A picklable HDF5 dataset reader (h5py objects are not): opens the file in each
    process on first use, read-only, and reads only the chunks a region meets."""

    def __init__(self, path, name: str, shape, dtype, chunks=None):
        self.path = str(path)
        self.name = name
        self.shape = tuple(int(n) for n in shape)
        self.dtype = np.dtype(dtype)
        self.ndim = len(self.shape)
        self.chunks = chunks
        self._file = None

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k != "_file"}

    def __setstate__(self, state):
        self.__dict__.update(state, _file=None)

    def __getitem__(self, key) -> np.ndarray:
        import h5py

        if self._file is None:
            self._file = h5py.File(self.path, "r")
        return self._file[self.name][key]


def _triplet(value, default: float) -> tuple[float, float, float]:
    arr = np.asarray(value if value is not None else default, dtype=np.float64).ravel()
    if arr.size == 1:
        arr = np.repeat(arr, 3)
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise InvalidDataError(f"spacing/origin must be 3 finite numbers, got {value!r}")
    return tuple(float(v) for v in arr)


def _volume_data(dask_array, spacing, origin, fmt, levels=(), source=None, **meta):
    return VolumeData(dask_array, spacing, origin, fmt,
                      {"levels": tuple(levels), "source": source, **meta})


# ------------------------------------------------------------------------------ Zarr


#: the metadata files that make a folder a Zarr store (v3, v2 array, v2 group)
ZARR_METADATA = ("zarr.json", ".zarray", ".zgroup")


def _is_zarr_folder(path: Path) -> bool:
    return any((path / n).is_file() for n in ZARR_METADATA)


def _ome_levels(path: Path):
    """(axes names, [(dataset path, scale, translation)], length unit) of an OME-Zarr image,
    or None."""
    from ome_zarr.io import parse_url
    from ome_zarr.reader import Multiscales, Reader

    location = parse_url(str(path))
    if location is None:
        return None
    for node in Reader(location)():
        ms = [s for s in node.specs if isinstance(s, Multiscales)]
        if not ms:
            continue
        described = node.metadata.get("axes", ["z", "y", "x"])
        axes = [a["name"] if isinstance(a, dict) else str(a) for a in described]
        # OME-NGFF names one unit per space axis ("micrometer"); the first one found is the grid's
        unit = next((a.get("unit") for a in described if isinstance(a, dict)
                     and a.get("type") == "space" and a.get("unit")), "")
        transforms = node.metadata.get("coordinateTransformations") or []
        levels = []
        for n, ds in enumerate(ms[0].datasets):
            scale = [1.0] * len(axes)
            shift = [0.0] * len(axes)
            for t in (transforms[n] if n < len(transforms) else []):
                if t.get("type") == "scale":
                    scale = list(t["scale"])
                elif t.get("type") == "translation":
                    shift = list(t["translation"])
            levels.append((ds, scale, shift))
        return axes, levels, canonical_unit(unit)
    return None


def _read_zarr(path: Path, t: int = 0):
    """An OME-Zarr image (multiscale levels) or a plain 3-D Zarr array, lazily; an image
    with a ``t`` axis at time index ``t`` (its other non-space axes at 0)."""
    import dask.array as da
    import zarr

    ome = _ome_levels(path)
    if ome is not None:
        axes, levels, unit = ome
        spatial = [n for n, a in enumerate(axes) if a in ("x", "y", "z")]
        if len(spatial) != 3:
            raise InvalidDataError(f"{path.name} has axes {axes}; a volume needs x, y and z")
        # volume axis a (x, y, z) is stored axis perm[a]; other axes (t, c) at index 0
        perm_full = [axes.index(a) for a in ("x", "y", "z")]
        out = []
        for ds, scale, shift in levels:
            arr = zarr.open_array(str(path / ds), mode="r")
            index = tuple(slice(None) if n in spatial else int(t) if axes[n] == "t" else 0
                          for n in range(arr.ndim))
            # a reader of the spatial axes only: drop leading t/c axes by fixed indices
            view = arr if arr.ndim == 3 else _Fixed(arr, index)
            kept = [n for n in range(arr.ndim) if n in spatial]
            perm = [kept.index(p) for p in perm_full]
            src = AxisSource(view, perm)
            dask_arr = da.from_array(src, chunks=tuple(
                arr.chunks[kept[p]] for p in perm), asarray=False)
            sp = _triplet([scale[p] for p in perm_full], 1.0)
            og = _triplet([shift[p] for p in perm_full], 0.0)
            out.append((dask_arr, sp, og, src))
        from splineviz.core.chunked import Level

        full = out[0]
        return _volume_data(full[0], full[1], full[2], "ome-zarr",
                            [Level(d, s, o) for d, s, o, _ in out[1:]], full[3],
                            axes="".join(axes), length_unit=unit)
    node = zarr.open(str(path), mode="r")
    if isinstance(node, zarr.Group):
        arrays = [a for _, a in node.arrays() if a.ndim == 3]
        if len(arrays) != 1:
            raise InvalidDataError(f"{path.name} is a Zarr group with {len(arrays)} 3-D arrays "
                                   "and no OME-Zarr multiscales; open the array's own folder")
        node = arrays[0]
    if node.ndim != 3:
        raise InvalidDataError(f"{path.name} holds a {node.ndim}-D array, not a volume")
    attrs = dict(node.attrs)
    src = AxisSource(node)
    return _volume_data(da.from_array(src, chunks=node.chunks, asarray=False),
                        _triplet(attrs.get("spacing"), 1.0), _triplet(attrs.get("origin"), 0.0),
                        "zarr", (), src)


class _Fixed:
    """An array with some axes fixed at an index (OME-Zarr t and c axes)."""

    def __init__(self, array, index):
        self.array = array
        self.index = index
        self.shape = tuple(n for n, i in zip(array.shape, index, strict=True)
                           if isinstance(i, slice))
        self.dtype = array.dtype

    def __getitem__(self, key):
        key = iter(tuple(key) + (slice(None),) * (len(self.shape) - len(tuple(key))))
        full = tuple(next(key) if isinstance(i, slice) else i for i in self.index)
        return self.array[full]


# ------------------------------------------------------------------------------ HDF5


def _read_hdf5(path: Path):
    """The 3-D dataset of an HDF5 file (the only one, or the one named data/volume/image)."""
    import dask.array as da
    import h5py

    found = []
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.ndim == 3:
                found.append((name, obj.shape, obj.dtype, obj.chunks, dict(obj.attrs)))

        f.visititems(visit)
    if not found:
        raise InvalidDataError(f"{path.name} holds no 3-D dataset")
    if len(found) > 1:
        named = [d for d in found if d[0].rsplit("/", 1)[-1] in ("data", "volume", "image")]
        if len(named) != 1:
            raise InvalidDataError(f"{path.name} holds several 3-D datasets "
                                   f"({', '.join(d[0] for d in found)}) and none is called "
                                   "data, volume or image")
        found = named
    name, shape, dtype, chunks, attrs = found[0]
    if attrs.get("spacing") is not None:
        spacing = _triplet(attrs["spacing"], 1.0)
    elif attrs.get("element_size_um") is not None:
        spacing = _triplet(np.asarray(attrs["element_size_um"])[::-1], 1.0)
    else:
        spacing = (1.0, 1.0, 1.0)
    src = H5Dataset(path, name, shape, dtype, chunks)
    # dask chunks: the stored chunks, or slabs of about 64 MiB for contiguous datasets
    dchunks = chunks or ("auto", shape[1], shape[2])
    return _volume_data(da.from_array(src, chunks=dchunks, asarray=False),
                        spacing, _triplet(attrs.get("origin"), 0.0), "hdf5", (), src,
                        dataset=name)


def _bare_hdf5(head: bytes) -> bool:
    """An HDF5 file that no other volume format claims by its content (MINC2 is HDF5 too):
    only then is it read as a bare dataset."""
    return head.startswith(HDF5_SIGNATURE) and not any(
        f.sniff(head) for f in formats("volume")
        if f.name != "hdf5" and f.sniff is not None and not f.folder)


register_format("ome-zarr", (".ome.zarr", ".zarr"), _read_zarr, None, kind="volume",
                folder=True, sniff=_is_zarr_folder,
                description="OME-Zarr image or Zarr array (folder; read lazily)")
register_format("zarr-metadata", (".json", ".zgroup", ".zattrs", ".zarray"),
                lambda p: _read_zarr(p.parent), None, kind="volume",
                sniff=lambda h: b'"zarr_format"' in h or b'"multiscales"' in h,
                description="the metadata file of a Zarr/OME-Zarr folder (opens the folder: "
                "file dialogs pick files)")
register_format("hdf5", (".h5", ".hdf5", ".hdf", ".he5"), _read_hdf5, None, kind="volume",
                sniff=_bare_hdf5,
                description="HDF5 3-D dataset (read lazily)")


def is_lazy(data) -> bool:
    """Whether reader output is a dask array (a chunked volume, not loaded)."""
    try:
        import dask.array as da
    except ImportError:  # pragma: no cover - a declared dependency
        return False
    return isinstance(data, da.Array)


def to_chunked_volume(vd, name: str, *, spacing=None, origin=None, oblique="direction"):
    """A :class:`~splineviz.core.chunked.ChunkedVolume` of lazily read :class:`VolumeData`.

    The file's direction is applied by :mod:`splineviz.io.geometry`'s rule, as
    :func:`~splineviz.io.volumes.to_volume` applies it, without reading a sample: axes
    transposed and flipped lazily (the dask array, the region reader through
    :class:`~splineviz.io.mapped.OrientedArray`, every coarser level; flips announced by a
    warning) and an oblique grid's rotation kept as the volume's ``direction``.

    Parameters
    ----------
    vd : VolumeData
        ``data`` a (n0, n1, n2) dask array in the file's index order.
    name : str
        File name for messages.
    spacing, origin : (3,) float, optional
        Replace the file's.
    oblique : {"direction", "resample", "error"}
        As :func:`~splineviz.io.volumes.read_volume`'s; resampling needs every sample, so
        a grid read brick by brick is never resampled: refused in one sentence, as is a
        sheared one.
    """
    from splineviz.core.chunked import ChunkedVolume
    from splineviz.core.volume import VolumeError
    from splineviz.io.geometry import affine_from, check_oblique, orientation, warn_flips
    from splineviz.io.mapped import OrientedArray

    sp = _triplet(vd.spacing if spacing is None else spacing, 1.0)
    og = _triplet(vd.origin if origin is None else origin, 0.0)
    orient = orientation(affine_from(sp, og, vd.direction), vd.data.shape, name,
                         space=vd.space)
    check_oblique(orient, name, oblique)
    if orient.oblique and (orient.sheared or oblique == "resample"):
        what = ("a sheared grid (its axes are not perpendicular)" if orient.sheared else
                f"an oblique scan (rotated by {orient.angle:.3g} degrees)")
        raise InvalidDataError(f"{name} is {what} and is read brick by brick (chunked, or too "
                               "large to render in one piece), so it cannot be resampled onto "
                               "axis-aligned axes; read it with oblique='direction' or "
                               "resample it with another tool")
    source, levels = vd.meta.get("source"), tuple(vd.meta.get("levels", ()))
    if not orient.identity:
        warn_flips(orient, name, stacklevel=4)
        source = None if source is None else OrientedArray(source, orient.perm, orient.flips)
        levels = tuple(_oriented_level(level, vd.direction, orient, name) for level in levels)
    try:
        return ChunkedVolume(orient.apply(vd.data), orient.spacing, orient.origin, levels,
                             name, source=source, unit=vd.meta.get("length_unit", ""),
                             direction=orient.volume_direction)
    except (VolumeError, ValueError) as exc:
        raise CorruptFileError(f"{name} cannot be used as a volume: {exc}") from None


def _oriented_level(level, direction, full, name: str):
    """A coarser :class:`~splineviz.core.chunked.Level` (file index order, the file's
    ``direction``) transposed and flipped as the full level ``full`` (an
    :class:`~splineviz.io.geometry.Orientation`), placed in the full volume's own frame:
    its first sample's world point turned back about the full level's origin."""
    from splineviz.core.chunked import Level
    from splineviz.io.geometry import affine_from, orientation

    own = orientation(affine_from(level.spacing, level.origin, direction), level.data.shape,
                      name)
    origin = np.asarray(own.origin, dtype=np.float64)
    if full.oblique:
        o = np.asarray(full.origin, dtype=np.float64)
        origin = o + full.rotation.T @ (origin - o)
    return Level(own.apply(level.data), own.spacing, tuple(float(v) for v in origin),
                 level.label)
