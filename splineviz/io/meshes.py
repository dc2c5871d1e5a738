"""Mesh and screenshot writers (and a mesh reader for sessions).

Meshes are ``pyvista.PolyData`` at this boundary (docs/api.md); a ``(vertices (V, 3),
faces (F, 3) int)`` pair is accepted too. Every write goes to a temporary file beside the
target and is renamed onto it only when complete.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from splineviz.io import _vtk
from splineviz.io._util import atomic_output, memory_budget, reader_errors, regular_input
from splineviz.io.errors import CorruptFileError, InvalidDataError, WriteError
from splineviz.io.registry import find_format, register_format


def as_polydata(mesh):
    """``pyvista.PolyData`` from a PolyData or a ``(vertices, faces)`` pair of triangles."""
    import pyvista as pv

    if isinstance(mesh, pv.PolyData):
        return mesh
    try:
        verts, faces = mesh
        verts = np.asarray(verts, dtype=np.float64)
        faces = np.asarray(faces)
    except (TypeError, ValueError):
        raise InvalidDataError("a mesh must be a pyvista.PolyData or (vertices, faces)") from None
    if verts.ndim != 2 or verts.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidDataError(f"mesh arrays must be (V, 3) and (F, 3), got {verts.shape} "
                               f"and {faces.shape}")
    if not np.issubdtype(faces.dtype, np.integer):
        raise InvalidDataError("mesh faces must be integer vertex indices")
    if faces.size and (faces.min() < 0 or faces.max() >= len(verts)):
        raise InvalidDataError("mesh faces refer to vertices that do not exist")
    if not np.all(np.isfinite(verts)):
        raise InvalidDataError("mesh vertices contain NaN or infinite coordinates")
    cells = np.hstack([np.full((len(faces), 1), 3), faces]).astype(np.int64).ravel()
    return pv.PolyData(verts, cells)


def _float32_normals(poly):
    """A shallow copy whose active point normals are float32: VTK's PLY writer only writes
    float normals (``nx ny nz``) and silently drops double ones."""
    name = poly.point_data.active_normals_name
    if name is None or poly.point_data[name].dtype == np.float32:
        return poly
    out = poly.copy(deep=False)
    out.point_data[name] = np.asarray(poly.point_data[name], dtype=np.float32)
    out.point_data.active_normals_name = name
    return out


def _read_back(poly, keeps_points: bool, name: str):
    """A check for :func:`atomic_output`: read the written mesh again and compare its
    counts. VTK's PLY and OBJ writers ignore failed writes (a full disk or the file-size
    limit gives a short file and success), so a short file is caught by reading it."""

    def verify(tmp: Path) -> None:
        try:
            back = _read_mesh_pv(tmp)
        except (CorruptFileError, InvalidDataError):
            back = None
        if back is None or back.GetNumberOfPolys() != poly.GetNumberOfPolys() or (
                keeps_points and back.n_points != poly.n_points):
            raise WriteError(f"writing {name} stopped before the end (disk full or file "
                             "too large?); the previous file, if any, is unchanged")

    return verify


def _vtk_writer(writer_cls, *, binary=True, keeps_points=True):
    def write(path: Path, mesh) -> None:
        poly = _float32_normals(as_polydata(mesh))
        with atomic_output(path, verify=_read_back(poly, keeps_points, path.name)) as tmp:
            w = writer_cls()
            w.SetFileName(str(tmp))
            w.SetInputData(poly)
            if binary and hasattr(w, "SetFileTypeToBinary"):
                w.SetFileTypeToBinary()
            with _vtk.captured_vtk_output() as out:
                ok = w.Write()
            err = _vtk.first_vtk_error(out[0], generic="the writer failed")
            if not ok or err:
                raise WriteError(f"cannot write {path.name}: {err or 'the writer failed'}")

    return write


def _writers():
    from vtkmodules.vtkIOGeometry import vtkOBJWriter, vtkSTLWriter
    from vtkmodules.vtkIOPLY import vtkPLYWriter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    # STL stores each triangle with its own corners: the reader merges them again, so only
    # the triangle count is compared
    return {"ply": _vtk_writer(vtkPLYWriter), "obj": _vtk_writer(vtkOBJWriter, binary=False),
            "stl": _vtk_writer(vtkSTLWriter, keeps_points=False),
            "vtp": _vtk_writer(vtkXMLPolyDataWriter, binary=False)}


def _lazy(name):
    def write(path, mesh):
        return _writers()[name](path, mesh)

    return write


def _vtk_reader(path: Path):
    """The VTK reader of a mesh file by suffix (OBJ, STL, VTP, legacy VTK), or None."""
    low = path.name.lower()
    if low.endswith(".obj"):
        from vtkmodules.vtkIOGeometry import vtkOBJReader

        return vtkOBJReader()
    if low.endswith(".stl"):
        from vtkmodules.vtkIOGeometry import vtkSTLReader

        return vtkSTLReader()
    if low.endswith(".vtp"):
        from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

        return vtkXMLPolyDataReader()
    if low.endswith(".vtk"):
        from vtkmodules.vtkIOLegacy import vtkPolyDataReader

        return vtkPolyDataReader()
    return None


def _read_mesh_ply(path: Path):
    """A PLY mesh through plyfile (complete and consistent, or a CorruptFileError), turned
    into PolyData here: VTK's PLY reader crashes the process on truncated or damaged files.

    Returns
    -------
    pyvista.PolyData
        Vertices, polygon faces and, when the file has ``nx ny nz``, point normals.
    """
    import pyvista as pv

    from splineviz.io.points import ply_vertices, read_ply_data

    ply = read_ply_data(path)
    v, names, pts = ply_vertices(ply, path)
    if len(pts) == 0:
        raise InvalidDataError(f"{path.name} holds no vertices")
    if not np.all(np.isfinite(pts)):
        raise InvalidDataError(f"{path.name} has NaN or infinite vertex coordinates")
    cells = np.zeros(0, dtype=np.int64)
    if "face" in ply and len(ply["face"].data):
        fdata = ply["face"].data
        key = next((k for k in ("vertex_indices", "vertex_index") if k in
                    (fdata.dtype.names or ())), None)
        if key is None:
            raise CorruptFileError(f"{path.name} has faces without vertex indices")
        col = fdata[key]
        if col.dtype != object:  # memory-mapped triangles: an (F, 3) array
            faces = [np.asarray(col).reshape(len(col), -1)]
        else:
            faces = [np.asarray(f) for f in col]
        try:
            cells = np.concatenate([np.column_stack([np.full(len(f), f.shape[1]), f])
                                    .ravel() if f.ndim == 2 else np.r_[len(f), f]
                                    for f in faces]).astype(np.int64)
            idx = np.concatenate([f.ravel() for f in faces]).astype(np.int64)
        except (ValueError, TypeError, OverflowError) as exc:
            raise CorruptFileError(f"{path.name} has malformed faces: {exc}") from None
        if idx.size and (idx.min() < 0 or idx.max() >= len(pts)):
            raise CorruptFileError(f"{path.name} has faces that refer to vertices it does "
                                   "not have")
    mesh = pv.PolyData(pts, cells) if cells.size else pv.PolyData(pts)
    if all(c in names for c in ("nx", "ny", "nz")):
        mesh.point_data["Normals"] = np.column_stack([np.asarray(v[c], np.float32)
                                                     for c in ("nx", "ny", "nz")])
    return mesh


def _read_mesh_pv(path: Path):
    """Any mesh pyvista/VTK reads (PLY, OBJ, STL, VTP, legacy VTK)."""
    import pyvista as pv

    if path.name.lower().endswith(".ply"):
        return _read_mesh_ply(path)

    reader = _vtk_reader(path)
    if reader is None:
        with _vtk.captured_vtk_output() as out, warnings.catch_warnings():
            # pyvista repeats VTK's errors as warnings and log records; the error is
            # reported once, below, as a CorruptFileError
            warnings.simplefilter("ignore")
            try:
                mesh = pv.read(str(path))
            except (ValueError, OSError, KeyError) as exc:
                raise CorruptFileError(f"{path.name} is not a readable mesh: {exc}") from None
        err = _vtk.first_vtk_error(out[0])
        if err:
            raise CorruptFileError(f"{path.name} cannot be read: {err}")
    else:
        if path.name.lower().endswith(".vtp"):
            _vtk.check_xml_appended(path, path.name, memory_budget())
        # the VTK reader run directly: its errors are captured, nothing reaches stderr
        reader.SetFileName(str(path))
        _vtk.run_vtk(reader, path.name)
        mesh = pv.wrap(reader.GetOutput())
    if not isinstance(mesh, pv.PolyData):
        mesh = mesh.extract_surface()
    if mesh.n_points == 0:
        raise InvalidDataError(f"{path.name} holds no vertices")
    if not np.isfinite(np.asarray(mesh.points)).all():
        raise InvalidDataError(f"{path.name} has NaN or infinite vertex coordinates")
    return mesh


for _name, _exts, _desc in (("ply", (".ply",), "Stanford PLY (binary)"),
                            ("obj", (".obj",), "Wavefront OBJ"),
                            ("stl", (".stl",), "STL (binary)"),
                            ("vtp", (".vtp",), "VTK XML PolyData")):
    register_format(_name, _exts, _read_mesh_pv, _lazy(_name), kind="mesh", description=_desc)


def _write_png(path: Path, image) -> None:
    from PIL import Image

    arr = np.asarray(image)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4) or arr.dtype != np.uint8 or 0 in arr.shape:
        raise InvalidDataError(f"a screenshot must be an (H, W, 3|4) uint8 image, got "
                               f"{arr.shape} {arr.dtype}")
    with atomic_output(path) as tmp:
        Image.fromarray(np.ascontiguousarray(arr)).save(str(tmp), format="PNG")


def _read_png(path: Path):
    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            # a decompression-bomb warning is answered by the error below, not printed
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as im:
                return np.asarray(im.convert("RGBA"))
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError, EOFError,
            Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise CorruptFileError(f"{path.name} is not a readable PNG image: {exc}") from None


register_format("png", (".png",), _read_png, _write_png, kind="image",
                sniff=lambda h: h.startswith(b"\x89PNG"), description="PNG image")


def write_mesh(path, mesh, *, format=None) -> Path:
    """Write a triangle mesh as PLY, OBJ, STL or VTP, atomically.

    Parameters
    ----------
    path : path-like
    mesh : pyvista.PolyData or (vertices (V, 3), faces (F, 3))
    format : str, optional

    Returns
    -------
    Path
    """
    p = Path(os.fspath(path)).expanduser()
    find_format(p, "mesh", mode="write", name=format).writer(p, mesh)
    return p


def read_mesh(path, *, format=None):
    """Read a mesh file -> ``pyvista.PolyData``."""
    p = regular_input(path)
    fmt = find_format(p, "mesh", name=format)
    with reader_errors(p.name, fmt.name):
        return fmt.reader(p)


def write_screenshot(path, image) -> Path:
    """Write an (H, W, 3|4) uint8 image (rows top to bottom) as PNG, atomically."""
    p = Path(os.fspath(path)).expanduser()
    find_format(p, "image", mode="write").writer(p, image)
    return p


def read_image(path) -> np.ndarray:
    """Read a PNG -> (H, W, 4) uint8."""
    p = regular_input(path)
    fmt = find_format(p, "image")
    with reader_errors(p.name, fmt.name):
        return fmt.reader(p)
