"""Spline isosurfaces as meshes (for "Export mesh").

The mesh is the isosurface *of the spline*: a flying-edges mesh of spline samples on a refined
grid whose vertices are moved onto s(x) = iso by Newton steps along the spline gradient, with
the exact spline normals. (The ray caster shows the surface exactly; this is its export.)
"""

from __future__ import annotations

import numpy as np

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
    mesh.points = pts
    mesh.point_data.active_normals = normals
    return mesh


def export_mesh(scene, node, path, clip: bool = True) -> str:
    """Write a mesh node, or an isosurface node meshed on a refined grid
    (:func:`spline_isosurface`), with normals; returns the path written.

    ``clip``: cut the mesh by the planes that cut the object in the view
    (:meth:`splineviz.model.Scene.planes_cutting`; ParaView's Clip before Save Data).
    """
    import pyvista as pv

    import splineviz as sv
    from splineviz.core.errors import SplinevizError
    from splineviz.model import IsosurfaceNode, MeshNode

    if isinstance(node, MeshNode):
        mesh = node.to_polydata()
    elif isinstance(node, IsosurfaceNode):
        vol = scene.volume_of(node)
        mesh = spline_isosurface(sv.build_spline(vol.active, node.model, **node.model_options()),
                                 node.isovalue)
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
