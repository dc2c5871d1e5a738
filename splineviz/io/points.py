"""Point-cloud readers.

Convention: a reader returns :class:`PointData` with ``points`` (N, 3) float64, optional
``normals`` (N, 3) float64 and ``colors`` (N, 3 or 4) uint8; :func:`read_points` validates it
and returns a :class:`~splineviz.PointCloud`. Libraries: plyfile (PLY, ascii and binary of
either endianness), NumPy text parsing (XYZ), pypcd4 (PCD), VTK (OBJ, STL) and meshio (OFF).
Counts announced in headers are compared with the file size before anything is allocated.
"""

from __future__ import annotations

import io
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from splineviz.core.points import PointCloud
from splineviz.io import _vtk
from splineviz.io._util import memory_budget, reader_errors, regular_input
from splineviz.io.errors import (
    CorruptFileError,
    DataSizeError,
    DataTooLargeError,
    FileFormatError,
    InvalidDataError,
)
from splineviz.io.registry import find_format, register_format

#: relative size (of the bounding-box diagonal) below which a point set counts as collinear
COLLINEAR_RTOL = 1e-9
#: fewest distinct points that can span a surface
MIN_POINTS = 3
#: fewest bytes one ascii vertex can take ("0 0 0\n")
MIN_ASCII_VERTEX_BYTES = 6


@dataclass
class PointData:
    """Points as read from a file.

    Attributes
    ----------
    points : (N, 3) float64
    normals : (N, 3) float64 or None
    colors : (N, 3) or (N, 4) uint8 or None
    format : str
    meta : dict
    """

    points: np.ndarray
    normals: np.ndarray | None = None
    colors: np.ndarray | None = None
    format: str = ""
    meta: dict = field(default_factory=dict)


def _check_count(count: int, path: Path, bytes_per_point: int) -> None:
    if count < 0:
        raise CorruptFileError(f"{path.name} announces a negative number of points")
    size = path.stat().st_size
    if count * bytes_per_point > size:
        raise DataSizeError(
            f"{path.name} announces {count:,} points but is only {size:,} bytes long"
        )
    if count * 3 * 8 * 3 > memory_budget():
        raise DataTooLargeError(f"{path.name} announces {count:,} points, too many for memory")


# ---------------------------------------------------------------------------- PLY
_TRIANGLES = {"face": {"vertex_indices": 3, "vertex_index": 3}}


def read_ply_data(path: Path):
    """Parse a PLY file completely with plyfile -> ``PlyData`` (payload length checked
    against the header's counts); every failure is a :class:`CorruptFileError`. Shared by
    the point and mesh readers: VTK's PLY reader crashes the process on truncated files."""
    from plyfile import PlyData, PlyElementParseError, PlyHeaderParseError, PlyParseError

    try:
        # ascii files are opened as text: plyfile would otherwise wrap the binary handle in
        # a TextIOWrapper it never closes. Binary payloads are memory-mapped, so plyfile
        # checks the length against the header's counts before touching data.
        text = re.search(rb"^format\s+ascii", _head(path, 4096), re.M) is not None
        mode = {"mode": "r", "encoding": "latin-1", "newline": ""} if text else {"mode": "rb"}
        with open(path, **mode) as fh:
            try:
                # triangle faces of known length can be memory-mapped too, not parsed row by
                # row as plyfile parses lists; other meshes take the general path
                ply = PlyData.read(fh, mmap="c", known_list_len=_TRIANGLES)
            except PlyElementParseError as exc:
                if "unexpected list length" not in str(exc):
                    raise
                fh.seek(0)
                ply = PlyData.read(fh, mmap="c")
            for el in ply.elements:
                _ = el.data  # memory-mapped: touch while the file is open
        return ply
    except (PlyParseError, PlyHeaderParseError) as exc:
        raise CorruptFileError(f"{path.name} is not a valid PLY file: {exc}") from None
    except (ValueError, EOFError, UnicodeDecodeError, MemoryError, TypeError, IndexError,
            OverflowError) as exc:
        raise CorruptFileError(f"{path.name} has a damaged PLY payload: {exc}") from None


def ply_vertices(ply, path: Path):
    """The vertex element of a parsed PLY file: its records, their field names and the
    (N, 3) float64 coordinates; :class:`InvalidDataError` without vertices or x, y, z.
    Shared by the point and mesh readers."""
    if "vertex" not in ply:
        raise InvalidDataError(f"{path.name} has no vertex element")
    v = ply["vertex"].data
    names = v.dtype.names or ()
    if not all(c in names for c in "xyz"):
        raise InvalidDataError(f"{path.name} has vertices without x, y, z")
    return v, names, np.column_stack([np.asarray(v[c], dtype=np.float64) for c in "xyz"])


def _read_ply(path: Path) -> PointData:
    ply = read_ply_data(path)
    try:
        v, names, pts = ply_vertices(ply, path)
        normals = None
        if all(c in names for c in ("nx", "ny", "nz")):
            normals = np.column_stack([np.asarray(v[c], np.float64)
                                       for c in ("nx", "ny", "nz")])
        colors = None
        for keys in (("red", "green", "blue", "alpha"), ("red", "green", "blue"),
                     ("diffuse_red", "diffuse_green", "diffuse_blue")):
            if all(k in names for k in keys):
                colors = np.column_stack([np.asarray(v[k]) for k in keys])
                if colors.dtype.kind == "f":  # float colours are in [0, 1]
                    colors = np.clip(colors * 255 + 0.5, 0, 255)
                colors = colors.astype(np.uint8)
                break
    except InvalidDataError:
        raise
    except (ValueError, TypeError) as exc:
        raise CorruptFileError(f"{path.name} has a damaged PLY payload: {exc}") from None
    if ply.text:
        fmt = "ascii"
    else:
        fmt = "binary_big_endian" if ply.byte_order == ">" else "binary_little_endian"
    return PointData(pts, normals, colors, "ply", {"encoding": fmt})


# ---------------------------------------------------------------------------- XYZ
def _read_xyz(path: Path) -> PointData:
    """Whitespace- or comma-separated ``x y z`` or ``x y z nx ny nz`` rows; ``#`` comments."""
    # the most rows the file can hold must fit in memory before it is parsed
    _check_count(path.stat().st_size // MIN_ASCII_VERTEX_BYTES, path, MIN_ASCII_VERTEX_BYTES)
    text = path.read_bytes()
    if b"\x00" in text[:4096]:
        raise CorruptFileError(f"{path.name} is binary, not an XYZ text file")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # an empty file warns in NumPy: make it an error
            arr = np.loadtxt(io.BytesIO(text.replace(b",", b" ")), comments="#", ndmin=2,
                             dtype=np.float64)
    except UserWarning:
        raise InvalidDataError(f"{path.name} holds no points") from None
    except ValueError as exc:
        raise CorruptFileError(f"{path.name} has a malformed row: {exc}") from None
    if arr.size == 0:
        raise InvalidDataError(f"{path.name} holds no points")
    if arr.shape[1] not in (3, 6):
        raise CorruptFileError(
            f"{path.name} has {arr.shape[1]} columns; XYZ needs 3 (x y z) or 6 (with normals)"
        )
    return PointData(arr[:, :3].copy(), arr[:, 3:].copy() if arr.shape[1] == 6 else None,
                     None, "xyz")


# ---------------------------------------------------------------------------- PCD
_PCD_KEY = re.compile(rb"^(FIELDS|SIZE|COUNT|POINTS|DATA|WIDTH|HEIGHT)\s+(.*?)\s*$", re.M)


def _read_pcd(path: Path) -> PointData:
    """Point Cloud Library PCD through pypcd4. The header counts are checked against the file
    size first: a reader allocates whatever POINTS says."""
    head = _head(path, 8192)
    keys = {k.decode(): v.decode("latin-1") for k, v in _PCD_KEY.findall(head)}
    if "POINTS" not in keys or "DATA" not in keys or "FIELDS" not in keys:
        raise CorruptFileError(f"{path.name} lacks the FIELDS, POINTS or DATA header lines")
    try:
        count = int(keys["POINTS"])
        sizes = [int(s) for s in keys.get("SIZE", "4 4 4").split()]
        counts = [int(c) for c in keys.get("COUNT", " ".join("1" * len(sizes))).split()]
    except ValueError:
        raise CorruptFileError(f"{path.name} has a malformed PCD header") from None
    fields = keys["FIELDS"].split()
    if not all(c in fields for c in "xyz"):
        raise InvalidDataError(f"{path.name} has no x, y, z fields")
    mode = keys["DATA"].split()[0].lower() if keys["DATA"].split() else ""
    if mode not in ("ascii", "binary", "binary_compressed"):
        raise CorruptFileError(f"{path.name} has an unknown DATA mode {keys['DATA']!r}")
    per_point = MIN_ASCII_VERTEX_BYTES if mode != "binary" else sum(
        s * c for s, c in zip(sizes, counts, strict=False))
    if mode == "binary_compressed":
        per_point = 0  # compressed size says nothing; the byte budget still applies
    _check_count(count, path, per_point)
    if mode == "ascii":  # missing ascii rows must not be read as zeros: count them first
        body = path.read_bytes().split(b"\nDATA", 1)[-1].split(b"\n", 1)[-1]
        rows = sum(1 for ln in body.splitlines() if ln.strip())
        if rows != count:
            raise DataSizeError(f"{path.name} announces {count} points but holds {rows} rows")
    from pypcd4 import PointCloud as PcdCloud

    data = PcdCloud.from_path(path).pc_data  # structured array, one field per PCD field
    if len(data) != count:
        raise CorruptFileError(f"{path.name} announces {count} points but {len(data)} could "
                               f"be read")

    def columns(names):  # (N, 3) float64, or None when a field is missing
        if not all(n in data.dtype.names for n in names):
            return None
        return np.column_stack([data[n] for n in names]).astype(np.float64)

    pts = columns(("x", "y", "z"))
    normals = columns(("normal_x", "normal_y", "normal_z"))
    # PCL packs a colour as the four bytes of one field (``rgb`` float32, ``rgba`` uint32)
    packed = next((f for f in ("rgb", "rgba") if f in data.dtype.names), None)
    colors = (PcdCloud.decode_rgb(np.ascontiguousarray(data[packed]))
              if packed is not None and data.dtype[packed].itemsize == 4 else None)
    return PointData(pts, normals, colors, "pcd", {"data": mode})


# ---------------------------------------------------------------------------- meshes' vertices
def _read_vtk_polydata(reader_cls, path: Path, fmt: str) -> PointData:
    from vtkmodules.util.numpy_support import vtk_to_numpy

    reader = reader_cls()
    reader.SetFileName(str(path))
    _vtk.run_vtk(reader, path.name)
    out = reader.GetOutput()
    if out is None or out.GetPoints() is None:
        raise InvalidDataError(f"{path.name} holds no vertices")
    pts = np.asarray(vtk_to_numpy(out.GetPoints().GetData()), dtype=np.float64)
    normals = None
    nrm = out.GetPointData().GetNormals()
    if nrm is not None and nrm.GetNumberOfTuples() == len(pts):
        normals = np.asarray(vtk_to_numpy(nrm), dtype=np.float64)
    return PointData(pts.copy(), normals, None, fmt, {"cells": int(out.GetNumberOfCells())})


def _read_obj(path: Path) -> PointData:
    from vtkmodules.vtkIOGeometry import vtkOBJReader

    return _read_vtk_polydata(vtkOBJReader, path, "obj")


def _read_stl(path: Path) -> PointData:
    from vtkmodules.vtkIOGeometry import vtkSTLReader

    return _read_vtk_polydata(vtkSTLReader, path, "stl")


def _read_off(path: Path) -> PointData:
    """Geomview OFF through meshio (Open3D returns garbage for truncated files)."""
    import meshio
    from meshio import off

    m = re.match(rb"\s*[CN]*OFF\s+(?:#[^\n]*\n\s*)*(\d+)", _head(path, 4096))
    if m is None:
        raise CorruptFileError(f"{path.name} does not start with an OFF header and counts")
    _check_count(int(m.group(1)), path, MIN_ASCII_VERTEX_BYTES)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # the format's own reader: meshio.read prints a failed read and calls
            # sys.exit(1) instead of raising
            mesh = off.read(str(path))
    except (meshio.ReadError, ValueError, IndexError, EOFError) as exc:
        raise CorruptFileError(f"{path.name} is not a valid OFF file: {exc}") from None
    return PointData(np.asarray(mesh.points, dtype=np.float64), None, None, "off")


def _head(path: Path, n: int) -> bytes:
    with open(path, "rb") as fh:
        return fh.read(n)


register_format("ply", (".ply",), _read_ply, None, kind="points",
                sniff=lambda h: h.startswith(b"ply"), description="Stanford PLY")
register_format("xyz", (".xyz", ".xyzn", ".txt", ".pts", ".csv"), _read_xyz, None,
                kind="points", description="XYZ text (x y z [nx ny nz])")
register_format("pcd", (".pcd",), _read_pcd, None, kind="points",
                sniff=lambda h: b"\nFIELDS" in h and b"\nDATA" in h, description="PCL PCD")
register_format("obj", (".obj",), _read_obj, None, kind="points",
                sniff=None, description="Wavefront OBJ vertices")
register_format("stl", (".stl",), _read_stl, None, kind="points",
                sniff=None, description="STL vertices")
register_format("off", (".off",), _read_off, None, kind="points",
                sniff=lambda h: re.match(rb"\s*[CN]*OFF\b", h) is not None,
                description="Geomview OFF vertices")


def load_point_data(path, *, format=None) -> PointData:
    """Read a point file as stored (see :func:`read_points`)."""
    p = regular_input(path)
    fmt = find_format(p, "points", name=format)
    with reader_errors(p.name, fmt.name):
        pd = fmt.reader(p)
    if not isinstance(pd, PointData):
        raise FileFormatError(f"the {fmt.name} reader returned {type(pd).__name__}, "
                              "not PointData")
    return pd


def validate_point_data(pd: PointData, name: str, *, dedupe: bool = True) -> PointData:
    """Refuse empty, non-finite and degenerate point sets; merge exact duplicates.

    A set is degenerate if its points do not span a plane: all equal, or collinear within
    :data:`COLLINEAR_RTOL` of the bounding-box diagonal (its second singular value).
    """
    pts = np.asarray(pd.points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InvalidDataError(f"{name} gives points of shape {pts.shape}, not (N, 3)")
    if len(pts) == 0:
        raise InvalidDataError(f"{name} holds no points")
    bad = ~np.all(np.isfinite(pts), axis=1)
    if bad.any():
        raise InvalidDataError(f"{name} has {int(bad.sum())} points with NaN or infinite "
                               "coordinates")
    normals = pd.normals
    if normals is not None:
        normals = np.asarray(normals, dtype=np.float64)
        if normals.shape != pts.shape or not np.all(np.isfinite(normals)):
            raise InvalidDataError(f"{name} has NaN, infinite or misshapen normals")
    colors = pd.colors
    meta = dict(pd.meta)
    if dedupe:
        _, first = np.unique(pts, axis=0, return_index=True)
        if len(first) < len(pts):
            keep = np.sort(first)
            meta["duplicates_removed"] = int(len(pts) - len(keep))
            pts = pts[keep]
            normals = None if normals is None else normals[keep]
            colors = None if colors is None else np.asarray(colors)[keep]
    if len(np.unique(pts, axis=0)) < MIN_POINTS:
        raise InvalidDataError(
            f"{name} has only {len(np.unique(pts, axis=0))} distinct point(s); a surface "
            f"needs at least {MIN_POINTS}"
        )
    centred = pts - pts.mean(axis=0)
    sv = np.linalg.svd(centred[:: max(1, len(pts) // 100000)], compute_uv=False)
    if sv[1] <= COLLINEAR_RTOL * max(sv[0], np.finfo(float).tiny):
        raise InvalidDataError(f"the points of {name} are collinear and span no surface")
    return PointData(pts, normals, colors, pd.format, meta)


def read_points(path, *, format=None, dedupe: bool = True) -> PointCloud:
    """Read a point cloud: PLY, XYZ (+normals), PCD, or the vertices of OBJ/OFF/STL.

    Parameters
    ----------
    path : path-like
    format : str, optional
        Force a registered points format by name.
    dedupe : bool
        Merge exactly repeated points (keeping the first); repeated points break the
        Delaunay-based connectivity of thesis ch. 7.

    Returns
    -------
    PointCloud
        ``points`` (N, 3) float64 and ``normals`` (N, 3) or None.

    Raises
    ------
    SplinevizError
        A subclass from :mod:`splineviz.io.errors` with a one-sentence message.
    """
    name = Path(os.fspath(path)).name
    pd = validate_point_data(load_point_data(path, format=format), name, dedupe=dedupe)
    return PointCloud(pd.points, pd.normals)
