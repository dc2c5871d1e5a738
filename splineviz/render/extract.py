"""Spline isosurfaces as meshes (for "Export mesh").

The mesh is the isosurface *of the spline*: a flying-edges mesh of spline samples on a refined
grid whose vertices are moved onto s(x) = iso by Newton steps along the spline gradient, with
the exact spline normals. (The ray caster shows the surface exactly; this is its export.)
"""

from __future__ import annotations

import numpy as np


def project_to_isosurface(spline, points: np.ndarray, iso: float, steps: int = 6):
    """Newton steps x <- x - (s(x) - iso) grad s / |grad s|^2, kept inside the data box.

    Parameters
    ----------
    spline : Spline
    points : (N, 3) starting points near the isosurface
    iso : float

    Returns
    -------
    points : (N, 3) projected points
    normals : (N, 3) unit normals -grad s / |grad s| there (VTK's contour convention: they point
        to lower values); zero where the gradient vanishes
    """
    lo = np.array([b[0] for b in spline.bounds])
    hi = np.array([b[1] for b in spline.bounds])
    x = np.asarray(points, dtype=np.float64).copy()
    # vertices on a face of the box slide within that face (the cut of the surface stays exact)
    tol = 1e-9 * np.max(hi - lo)
    free = ~((np.abs(x - lo) < tol) | (np.abs(x - hi) < tol))
    step_limit = 0.5 * np.min(spline.volume.spacing)
    for _ in range(steps):
        v, g = spline.value_gradient(x)
        g = g * free
        g2 = np.einsum("nc,nc->n", g, g)
        ok = g2 > 1e-30
        delta = np.zeros_like(x)
        delta[ok] = ((v[ok] - iso) / g2[ok])[:, None] * g[ok]
        # never move further than half a voxel: a vertex belongs to the sheet it started on
        norm = np.linalg.norm(delta, axis=1)
        scale = np.minimum(1.0, step_limit / np.maximum(norm, 1e-300))
        x = np.clip(x - delta * scale[:, None], lo, hi)
    g = spline.gradient(x)
    n = np.linalg.norm(g, axis=1)
    normals = np.divide(-g, n[:, None], out=np.zeros_like(g), where=n[:, None] > 0)
    return x, normals


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
