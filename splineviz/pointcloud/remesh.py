"""``sv.remesh``: point cloud to a high-quality triangle mesh (thesis chapter 7).

Pipeline: k-nearest (or, for fixed-width fits, Cocone) connectivity -> local polynomials
(:class:`Projector`) -> curvature-adapted guidance field -> advancing front -> valence flips
and tangential relaxation on the surface -> least-squares vertex heights -> sharp creases
(:func:`~splineviz.pointcloud.creases.sharpen`).  Returns a
``pyvista.PolyData`` (the mesh boundary type of docs/api.md).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from splineviz.core.errors import SplinevizError
from splineviz.core.points import PointCloud
from splineviz.pointcloud.advancing_front import BORDER_NEIGHBOURS, AdvancingFront
from splineviz.pointcloud.cocone import cocone_connectivity
from splineviz.pointcloud.creases import sharpen
from splineviz.pointcloud.guidance import guidance_field
from splineviz.pointcloud.projection import Projector
from splineviz.pointcloud.relaxation import optimize, vertex_normals
from splineviz.pointcloud.surface_fit import fit_heights


class RemeshError(SplinevizError, ValueError):
    """Invalid input or parameters for :func:`remesh`."""


@dataclass
class RemeshReport:
    """What a remesh run did: stage timings (s; ``creases_s``, part of ``optimize_s``, is
    :func:`~splineviz.pointcloud.creases.sharpen`'s), front event counts, parameters."""

    timings: dict = field(default_factory=dict)
    front: dict = field(default_factory=dict)
    parameters: dict = field(default_factory=dict)
    flips: int = 0


def _as_cloud(pc) -> PointCloud:
    if isinstance(pc, PointCloud):
        return pc
    try:
        return PointCloud(np.asarray(pc, dtype=np.float64))
    except (TypeError, ValueError) as exc:
        if isinstance(exc, SplinevizError):
            raise
        raise RemeshError("the input must be a PointCloud or an (N, 3) array of points") from exc


#: largest ratio of a cloud's second to first principal extent that counts as a line: a
#: cloud this thin has no surface to sample (a "mesh" of it would be a few slivers)
COLLINEAR_RATIO = 1e-3


#: fewest points :func:`remesh` triangulates: the advancing front looks at the
#: ``BORDER_NEIGHBOURS`` nearest input points of every new vertex
MIN_POINTS = BORDER_NEIGHBOURS


def _check_spans_a_surface(points: np.ndarray) -> None:
    """Refuse, before any work, clouds without a surface to mesh: too few points for the
    front's neighbourhoods, or points on (nearly) one line.

    Parameters
    ----------
    points : (N, 3) float ndarray
    """
    if len(points) < MIN_POINTS:
        raise RemeshError(f"at least {MIN_POINTS} points are needed to build a mesh, got "
                          f"{len(points)}")
    extent = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    if extent[1] <= COLLINEAR_RATIO * max(extent[0], np.finfo(float).tiny):
        raise RemeshError("the points lie on a line (their width is under "
                          f"{COLLINEAR_RATIO:g} of their length), so they span no surface")


#: pieces of the mesh with fewer triangles than this are dropped when a larger piece exists:
#: the front seeds any ten input points it left far behind, and on range scans with noise the
#: points thrown past a crease by rays at a steep angle make such seeds (19 pieces of 1-18
#: triangles on ``splineviz bench cad-scans``' airplane at 0.5 % noise, up to 4.8 % of the
#: diagonal off the true surface; dropping them took its Hausdorff distance to 0.64 %)
MIN_PIECE_FACES = 32


def drop_specks(vertices: np.ndarray, faces: np.ndarray):
    """The mesh without its connected pieces of fewer than ``MIN_PIECE_FACES`` triangles,
    unless none is larger; unused vertices removed.

    Parameters
    ----------
    vertices : (V, 3)
    faces : (F, 3) int

    Returns
    -------
    vertices (V', 3), faces (F', 3)
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if len(faces) == 0:
        return vertices, faces
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    n, label = connected_components(
        coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])),
                   shape=(len(vertices), len(vertices))), directed=False)
    if n == 1:
        return vertices, faces
    size = np.bincount(label[faces[:, 0]], minlength=n)
    if size.max() < MIN_PIECE_FACES:
        return vertices, faces
    faces = faces[size[label[faces[:, 0]]] >= MIN_PIECE_FACES]
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    new_id = np.cumsum(used) - 1
    return vertices[used], new_id[faces]


def remesh(pc, edge_length: float | None = None, rho: float | None = None, progress=None, *,
           min_length: float | None = None, max_length: float | None = None,
           smoothing: float | None = None, optimize_mesh: bool = True,
           projector: Projector | None = None,
           fixed_degree: int | None = None, report: RemeshReport | None = None,
           sharp_creases: bool = True):
    """Triangulate a point cloud with near-equilateral, curvature-adapted triangles.

    Parameters
    ----------
    pc : PointCloud or (N, 3) array_like
    edge_length : float, optional
        Uniform target edge length (world units); overrides ``rho``.
    rho : float, optional
        Curvature adaptation: the angle (radians) one edge subtends on the osculating circle;
        smaller gives finer triangles where the surface bends.  Default 0.35.
    progress : callable, optional
        ``progress(fraction, message)``; return ``False`` to cancel (raises
        :class:`~splineviz.pointcloud.advancing_front.Cancelled`).
    min_length, max_length : float, optional
        Bounds of the adaptive edge length (defaults 1.5 and 5 times the median spacing).
    smoothing : float, optional
        Fixed Gaussian width of the local fits in units of the local spacing; by default the
        width is chosen per point from the noise in the data (:class:`Projector`).
    optimize_mesh : bool
        Run valence flips and tangential relaxation after the front, then fit the vertices
        to the surface in the least-squares sense
        (:func:`~splineviz.pointcloud.surface_fit.fit_heights`).
    projector : Projector, optional
        Reuse a precomputed projector (its own ``smoothing`` applies).
    fixed_degree : int, optional
        Fixed polynomial degree (MLS-style ablation) when no projector is given.
    report : RemeshReport, optional
        Filled with timings and front statistics.
    sharp_creases : bool
        With ``optimize_mesh``, find the sharp creases of the points (two planes meeting at
        an edge) and put the mesh's vertices near them onto the edge, its edges along it
        (:func:`~splineviz.pointcloud.creases.sharpen`); ``False`` keeps the smooth fits'
        rounded creases.

    Returns
    -------
    pyvista.PolyData
        Triangles oriented counter-clockwise around the outward normals.

    Examples
    --------
    >>> import numpy as np, splineviz as sv
    >>> rng = np.random.default_rng(1)
    >>> v = rng.normal(size=(2000, 3)); v /= np.linalg.norm(v, axis=1, keepdims=True)
    >>> mesh = sv.remesh(v, edge_length=0.2)
    >>> q = sv.mesh_quality(mesh)
    >>> q["boundary_edges"], q["non_manifold_edges"], q["radius_ratio_mean"] > 0.85
    (0, 0, True)
    """
    import pyvista as pv

    cloud = _as_cloud(pc)
    _check_spans_a_surface(np.asarray(cloud.points, dtype=np.float64))
    rep = report if report is not None else RemeshReport()
    rep.parameters = {"edge_length": edge_length, "rho": rho, "min_length": min_length,
                      "max_length": max_length, "smoothing": smoothing,
                      "fixed_degree": fixed_degree, "optimize_mesh": optimize_mesh,
                      "sharp_creases": sharp_creases}

    def stage(frac, message):
        if progress is not None and progress(frac, message) is False:
            from splineviz.pointcloud.advancing_front import Cancelled

            raise Cancelled("the triangulation was cancelled")

    t0 = time.perf_counter()
    stage(0.0, "connectivity and local surfaces")
    if projector is None and smoothing is None and fixed_degree is None:
        # the noise-aware projection's own k-nearest connectivity: no Delaunay
        # tetrahedralisation (Cocone's was a fifth of Lucy's CPU time and, memory-bound, most
        # of its wall time on a loaded machine); its sheet masks keep the two sides of thin
        # parts apart in the fits, and on the five bench clouds the meshes' 99th-percentile
        # distances to the points are as good or better (Lucy 0.451 -> 0.410 %)
        projector = Projector(cloud)
    elif projector is None:
        # the thesis' fixed-width and fixed-degree fits collect their neighbourhoods along
        # Cocone's graph, which keeps the two sides of thin parts apart
        projector = Projector(cloud, smoothing=smoothing, fixed_degree=fixed_degree,
                              connectivity=cocone_connectivity(cloud))
    t1 = time.perf_counter()
    field_ = guidance_field(projector, edge_length=edge_length, rho=rho, min_length=min_length,
                            max_length=max_length)
    stage(0.3, "advancing front")

    def front_progress(frac, message):
        return progress(0.3 + 0.6 * frac, message) if progress is not None else None

    front = AdvancingFront(projector, field_, front_progress)
    vertices, faces = drop_specks(*front.run())
    t2 = time.perf_counter()
    flips = 0
    creases_s = 0.0
    if optimize_mesh:
        stage(0.9, "valence flips and relaxation")
        vertices, faces, flips = optimize(vertices, faces, projector)
        # the least-squares fit of the triangles to the surface: flat triangles with corners
        # on the surface stay inside its bends (noisy bunny p99 points->mesh 0.550 -> 0.527 %,
        # kitten two-sided Hausdorff 1.077 -> 0.982 %)
        vertices = fit_heights(vertices, faces, projector)
        # last: the smooth fits (and the heights fitted to them) round a crease of a
        # scanned part into a band of wrong normals; its vertices go onto the intersection
        # of the two sides' planes and its edges along that line
        t_creases = time.perf_counter()
        if sharp_creases:
            vertices, faces, _, crease_flips = sharpen(vertices, faces, projector)
            flips += crease_flips
        creases_s = time.perf_counter() - t_creases
    t3 = time.perf_counter()
    stage(1.0, "done")
    rep.timings = {"projector_s": t1 - t0, "front_s": t2 - t1, "optimize_s": t3 - t2,
                   "creases_s": creases_s, "total_s": t3 - t0}
    rep.front = dict(vars(front.stats))
    rep.front.pop("events", None)
    rep.flips = flips
    cells = np.hstack([np.full((len(faces), 1), 3, dtype=np.int64), faces]).ravel()
    return pv.PolyData(vertices, cells)


def remesh_with_quality(points, edge_length=None, rho=None, job=None, *,
                        sharp_creases: bool = True) -> dict:
    """:func:`remesh` plus what a viewer shows of the result: ``{"vertices" (V, 3), "faces"
    (F, 3), "normals" (V, 3), "quality"}`` (:func:`~splineviz.pointcloud.quality.mesh_quality`
    against the points). ``job``: an object with ``progress(fraction, message)``, e.g. the
    GUI's job context; runs in a worker process there, so it returns plain arrays."""
    from splineviz.pointcloud.quality import mesh_quality

    progress = None if job is None else job.progress
    mesh = remesh(points, edge_length=edge_length, rho=rho, progress=progress,
                  sharp_creases=sharp_creases)
    if progress is not None:
        progress(None, "measuring the mesh")
    vertices = np.asarray(mesh.points, dtype=np.float64)
    faces = np.asarray(mesh.faces).reshape(-1, 4)[:, 1:].astype(np.int64)
    return {"vertices": vertices, "faces": faces, "normals": vertex_normals(vertices, faces),
            "quality": mesh_quality(mesh, reference=points)}
