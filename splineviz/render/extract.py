"""Spline isosurfaces as meshes (for "Export mesh").

The mesh is the isosurface *of the spline*: a flying-edges mesh of spline samples on a refined
grid whose vertices are moved onto s(x) = iso by Newton steps along the spline gradient, with
the exact spline normals. (The ray caster shows the surface exactly; this is its export.)
Meshes are in world: the spline's own frame turned by an oblique volume's direction
(:mod:`splineviz.core.frame`).
"""

from __future__ import annotations

import numpy as np

from splineviz.core import frame
from splineviz.core.isosurface import project_to_isosurface

#: most spline samples taken to mesh the isosurface (bounds the time of a mesh export)
MAX_SAMPLES = 4_000_000


def spline_isosurface(spline, iso: float, refine: int = 2):
    """pyvista.PolyData of the spline isosurface (vertices on s = iso, exact normals).

    The spline is sampled on the data grid refined ``refine`` times per axis (less if that
    exceeds :data:`MAX_SAMPLES`), meshed with flying edges, and the vertices are projected onto
    s = iso with :func:`project_to_isosurface`.
    """
    import pyvista as pv

    vol = spline.volume
    n = np.asarray(vol.shape)
    while refine > 1 and np.prod((n - 1) * refine + 1) > MAX_SAMPLES:
        refine -= 1
    dims = (n - 1) * refine + 1
    spacing = np.asarray(vol.spacing) / refine
    grid = pv.ImageData(dimensions=dims, spacing=spacing, origin=vol.origin)
    grid.point_data["values"] = spline.evaluate(np.asarray(grid.points))
    mesh = grid.contour([iso], scalars="values", method="flying_edges")
    if mesh.n_points == 0:
        return mesh
    pts, normals = project_to_isosurface(spline, np.asarray(mesh.points), iso)
    mesh.points = frame.to_world(vol, pts)
    mesh.point_data.active_normals = frame.vectors_to_world(vol, normals)
    return mesh


def front_isosurface(spline, iso: float, planes=(), **options):
    """pyvista.PolyData of the spline isosurface meshed by the advancing front on the spline
    (:func:`splineviz.pointcloud.spline_mesh.spline_front_mesh`: vertices on s = iso,
    curvature-adapted, well-shaped triangles, exact cuts by ``planes``), with normals."""
    from splineviz.pointcloud.spline_mesh import spline_front_mesh

    return _on_spline(spline_front_mesh, spline, iso, planes, **options)


def remesh_isosurface(spline, iso: float, planes=(), **options):
    """pyvista.PolyData of the spline isosurface meshed by flying edges and isotropic
    remeshing on the spline (:func:`splineviz.pointcloud.spline_remesh.spline_remesh`:
    vertices on s = iso, well-shaped triangles, exact cuts by ``planes``; far faster than the
    front on whole volumes), with normals."""
    from splineviz.pointcloud.spline_remesh import spline_remesh

    return _on_spline(spline_remesh, spline, iso, planes, **options)


def _on_spline(mesher, spline, iso, planes, **options):
    """A spline mesher's ``(vertices, faces, normals)`` as world pyvista.PolyData."""
    import pyvista as pv

    vol = spline.volume
    if len(planes):
        # the planes are world's; the spline is in its volume's frame
        planes = [tuple(p) for p in frame.planes_to_volume(vol, np.asarray(planes, float))]
    v, f, n = mesher(spline, iso, planes=planes, **options)
    mesh = pv.PolyData(frame.to_world(vol, v),
                       np.hstack([np.full((len(f), 1), 3), f]).astype(np.int64).ravel())
    mesh.point_data.active_normals = frame.vectors_to_world(vol, n)
    return mesh


#: mesh export methods for isosurfaces
EXPORT_METHODS = ("flying-edges", "front", "remesh")


def export_mesh(scene, node, path, clip: bool = True, method: str = "flying-edges") -> str:
    """Write a mesh node, or an isosurface node meshed on a refined grid
    (:func:`spline_isosurface`, ``method="flying-edges"``, fast), by the advancing front on
    the spline (:func:`front_isosurface`, ``method="front"``) or by isotropic remeshing on the
    spline (:func:`remesh_isosurface`, ``method="remesh"``), with normals; returns the path
    written.

    ``clip``: cut the mesh by the planes that cut the object in the view
    (:meth:`splineviz.model.Scene.planes_cutting`; ParaView's Clip before Save Data). The
    front and the remeshing cut exactly: the new vertices lie on the plane and on the spline
    surface.
    """
    import pyvista as pv

    import splineviz as sv
    from splineviz.core.errors import SplinevizError
    from splineviz.model import IsosurfaceNode, MeshNode

    if isinstance(node, MeshNode):
        mesh = node.to_polydata()
    elif isinstance(node, IsosurfaceNode):
        if method not in EXPORT_METHODS:
            raise SplinevizError(f"unknown mesh export method {method!r}; choose one of "
                                 f"{', '.join(EXPORT_METHODS)}")
        vol = scene.volume_of(node)
        spline = sv.build_spline(vol.active, node.model, **node.model_options())
        if method in ("front", "remesh"):
            planes = scene.planes_cutting(node) if clip else []
            mesher = front_isosurface if method == "front" else remesh_isosurface
            return str(sv.write_mesh(path, mesher(spline, node.isovalue, planes)))
        mesh = spline_isosurface(spline, node.isovalue)
    else:
        raise SplinevizError("select a mesh or an isosurface to export")
    planes = scene.planes_cutting(node) if clip else []
    for origin, normal in planes:
        # invert=False keeps the side the normal points to, as the ray caster does
        mesh = mesh.clip(normal=normal, origin=origin, invert=False)
    if planes:
        if not isinstance(mesh, pv.PolyData):
            mesh = mesh.extract_surface(algorithm="dataset_surface")
        mesh = mesh.triangulate()
    return str(sv.write_mesh(path, mesh))
