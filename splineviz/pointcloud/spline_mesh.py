"""Meshes of spline isosurfaces by the advancing front of chapter 7, with the spline itself as
the projector (thesis §7.3 with the volume's spline in place of the local polynomials).

* Projection: Newton steps onto ``s = iso`` along the exact spline gradient
  (:func:`splineviz.core.isosurface.project_to_isosurface`); normals ``-grad s / |grad s|``.
* Edge lengths: ``2 sin(rho / 2) / kappa`` with ``kappa`` the larger absolute principal
  curvature of the spline's isosurface (:mod:`splineviz.core.curvature`) at surface samples,
  clamped and graded like the point-cloud guidance field
  (:func:`splineviz.pointcloud.guidance.limit_gradation`).
* Samples: where the data cross the isovalue along grid edges, one per grid cell, projected
  onto the spline surface. They tell the front where the surface is (seeds, the data box's
  border) exactly as the input points of a scan do.
* One sheet: the front's tests see samples and front edges near a candidate triangle, not
  the surface between its corners. Every triangle must lie on one sheet of the spline surface
  (:func:`triangles_on_surface`: probes near ``s = iso``, not on both sides of it, corner
  normals less than a right angle apart), and edges are at most the distance along the
  normal to the next sheet (:func:`sheet_gaps`): leaves a voxel apart are not joined.
* Holes: where the front gives up edges (its point-cloud tests misjudge sharp folds), the
  border loops left inside the surface are closed by rings on the surface
  (:func:`fill_holes`); then valence flips and tangential relaxation
  (:func:`splineviz.pointcloud.relaxation.optimize`) with the spline as projector.
* Speed: for type-6 models (cubic-c1, super-quadratic) the projection, the one-sheet test
  and the sheet gaps run in compiled kernels (:mod:`.spline_kernels`): the front asks many
  small questions, and the vectorised evaluation's fixed overhead per call would dominate.
  Other models take the vectorised path.
* Clip planes: the front runs a little past each plane, then the mesh is cut there; vertices
  on the cut are put onto the exact section curve (plane and isosurface,
  :func:`splineviz.core.sections.project`), vertices closer than ``SNAP`` edge lengths to the
  plane are moved onto it first so that the cut leaves no slivers.

Conventions: ``vertices (V, 3)`` float64, ``faces (F, 3)`` int64 counter-clockwise seen from the
normals, ``normals (V, 3)`` unit.
"""

from __future__ import annotations

import functools
import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

from splineviz.core import sections
from splineviz.core.curvature import spline_curvatures
from splineviz.core.errors import SplinevizError
from splineviz.core.isosurface import project_to_isosurface
from splineviz.pointcloud.advancing_front import VERTEX_BUDGET, AdvancingFront, simple_loops
from splineviz.pointcloud.cocone import tree_query
from splineviz.pointcloud.guidance import GuidanceField, limit_gradation
from splineviz.pointcloud.relaxation import optimize
from splineviz.pointcloud.spline_kernels import compiled

#: default angle (radians) one edge subtends on the osculating circle: a chord of this angle
#: stands off the surface by 3 % of its length (the triangle counts and Hausdorff distances
#: it gives against flying edges: ``python -m splineviz.bench.spline_mesh``)
DEFAULT_RHO = 0.5
#: default edge-length bounds, in grid steps
DEFAULT_MIN_LENGTH = 0.4
DEFAULT_MAX_LENGTH = 6.0
#: growth of the target length per unit distance
GRADATION = 0.3
#: a vertex within this many target lengths of a clip plane is moved onto the plane
SNAP = 0.3
#: neighbours per sample in the gradation graph
GRAPH_NEIGHBOURS = 8
#: value tolerance of a vertex, relative to the data range
VALUE_TOL = 1e-9
#: at most this many surface samples (one per grid cell; coarser cells beyond)
MAX_SAMPLES = 600_000
#: the target edge length is at most this many times the distance, along the normal, from a
#: sample to the next sheet of the surface (the gap to a neighbouring leaf, the thickness of
#: a thin part): longer edges let a triangle reach across to the other sheet
GAP_FACTOR = 1.0
#: ... measured by marching the spline along both normal directions in steps of GAP_STEP
#: grid steps, starting GAP_START grid steps off the sample
GAP_STEP = 0.25
GAP_START = 0.25
#: a triangle lies on the surface when its samples (at most PROBE_SPACING grid steps apart)
#: are within SURFACE_DEVIATION of its longest side from s = iso (first-order distance
#: ``|s - iso| / |grad s|``; a chord of the curvature-adapted length deviates ~0.05 of it) ...
PROBE_SPACING = 0.5
SURFACE_DEVIATION = 0.15
#: ... and do not lie on both sides of the surface by more than SURFACE_CROSSING of its longest
#: side (a triangle that passes through a thin part of the object, e.g. a leaf)
SURFACE_CROSSING = 0.06
#: a triangle's probes never need to be nearer than this (grid steps) to the surface: the
#: smallest triangles sit where the curvature is highest, the first-order distance is least
#: exact there, and no gap narrower than this is resolved by the data
PROBE_FLOOR = 0.2
#: the triangles closing a hole the front left may stand this many grid steps off the surface
#: (a hole of the front's edge length is farther from the surface than that; triangles across
#: a gap between sheets stand off by half the gap, and face each other, see MAX_CORNER_TURN)
HOLE_SLACK = 0.4
#: the spline normals at a triangle's corners may differ by at most this angle: corners on
#: the two sides of a gap or of a thin part face each other (in the bonsai crop 5 of 42,000
#: triangles on one sheet exceed it)
MAX_CORNER_TURN = np.deg2rad(90.0)
#: at most this many probe subdivisions per side
MAX_PROBE_DIVISIONS = 16
#: the front stops beyond this many times the vertices the target lengths call for (a
#: front that runs over itself)
VERTEX_SLACK = 3.0
#: a valence flip may lower the smallest radius ratio of its two triangles to this fraction
#: (the point-cloud remesher's 0.6 refuses flips the relaxation after it evens out here: at
#: 0.4 the valence-6 share of the bonsai crop and the tooth rises from 71.9 / 75.3 % to
#: 74.4 / 77.0 %, the mean radius ratio falls by 0.0007 / 0.0004)
FLIP_KEEP = 0.4
#: at most this many seeds (the front's default is for one scanned object; an isosurface
#: such as the bonsai's leaves has many small pieces)
MAX_SPLINE_SEEDS = 5000


class SplineMeshError(SplinevizError, ValueError):
    """No spline mesh can be made (the isovalue is not crossed, bad parameters)."""


@dataclass(frozen=True, eq=False)
class _Samples:
    """What the front reads of a point cloud's connectivity: the k-d tree and how irregular
    the sampling is (grid samples are regular)."""

    tree: cKDTree
    graph: sparse.csr_matrix

    def void_ratio(self) -> float:
        return 1.0


class SplineProjector:
    """The projector interface of :class:`~splineviz.pointcloud.advancing_front.AdvancingFront`
    for the isosurface ``s = iso`` of a spline.

    Parameters
    ----------
    spline : Spline
    iso : float
    points : (N, 3) samples on the surface
    normals : (N, 3) their unit normals
    spacing : float, the samples' spacing
    """

    def __init__(self, spline, iso, points, normals, spacing):
        self.spline = spline
        self.iso = float(iso)
        self.points = points
        self.normals = normals
        self.scale = np.full(len(points), float(spacing))
        lo, hi = spline.volume.finite_range
        self.tol = VALUE_TOL * max(hi - lo, 1e-300)
        tree = cKDTree(points)
        dist, idx = tree_query(tree, points, GRAPH_NEIGHBOURS + 1)
        rows = np.repeat(np.arange(len(points)), GRAPH_NEIGHBOURS)
        graph = sparse.csr_matrix((dist[:, 1:].ravel(), (rows, idx[:, 1:].ravel())),
                                  shape=(len(points), len(points)))
        self.conn = _Samples(tree, graph.maximum(graph.T).tocsr())

    def project_with_normals(self, points, normal_hint=None):
        """Newton projection onto ``s = iso``: points ``(M, 3)`` and unit normals ``(M, 3)``;
        ``normal_hint`` is not needed (the spline's normals are consistent everywhere)."""
        # most points converge in one or two steps; a guess far off the surface needs more
        # of the half-voxel-limited steps
        return project_onto(self.spline, points, self.iso, 30, self.tol)

    def project(self, points):
        """Newton projection onto ``s = iso`` of ``(M, 3)`` points."""
        return self.project_with_normals(points)[0]


def project_onto(spline, points, iso: float, steps: int, tol: float | None = None):
    """Newton projection onto ``s = iso``
    (:func:`~splineviz.core.isosurface.project_to_isosurface`), by the compiled kernels
    (:mod:`.spline_kernels`) where they cover the model; each point then stops once within
    ``tol``, not when all are.

    Parameters
    ----------
    spline : Spline
    points : (M, 3)
    iso : float
    steps : int, most Newton steps
    tol : float, optional

    Returns
    -------
    points : (M, 3), normals : (M, 3) unit ``-grad s / |grad s|`` (zero where it vanishes)
    """
    fast = compiled(spline)
    if fast is None:
        return project_to_isosurface(spline, points, iso, steps=steps, tol=tol)
    return fast.project(points, iso, steps, tol)


def _values(spline, points):
    """Spline values ``(M,)`` at ``(M, 3)`` points (compiled where the kernels cover the
    model)."""
    fast = compiled(spline)
    return spline.evaluate(points) if fast is None else fast.value_gradient(points)[0]


def surface_samples(spline, iso: float, cell: float | None = None):
    """Points on ``s = iso`` near every grid edge whose data cross the isovalue.

    Parameters
    ----------
    spline : Spline
    iso : float
    cell : float, optional
        One sample per cube of this size (default one grid step, coarser when there would be
        more than ``MAX_SAMPLES``).

    Returns
    -------
    points : (N, 3), normals : (N, 3), cell : float
    """
    vol = spline.volume
    data = vol.values()  # the crossing test in float32 whatever the stored type
    found = []
    for axis in range(3):
        a = np.moveaxis(data, axis, 0)
        lo_v, hi_v = a[:-1], a[1:]
        hits = np.argwhere(((lo_v - iso) * (hi_v - iso) <= 0) & (lo_v != hi_v))
        if len(hits) == 0:
            continue
        i, j, k = hits.T
        f0, f1 = lo_v[i, j, k].astype(np.float64), hi_v[i, j, k].astype(np.float64)
        t = np.divide(iso - f0, f1 - f0, out=np.full_like(f0, 0.5), where=f1 != f0)
        idx = np.stack([i, j, k], axis=1).astype(np.float64)
        idx[:, 0] += t
        # the moved array's axes are (axis, then the other two in order): back to (x, y, z)
        xyz = np.empty_like(idx)
        xyz[:, [axis] + [d for d in range(3) if d != axis]] = idx
        found.append(xyz)
    if not found:
        raise SplineMeshError(f"the isovalue {iso:g} is not crossed by the data")
    index = np.concatenate(found)
    world = vol.index_to_world(index)
    step = float(np.min(vol.spacing))
    cell = step if cell is None else float(cell)
    while True:
        keys = np.floor(world / cell).astype(np.int64)
        _, first = np.unique(keys, axis=0, return_index=True)
        if len(first) <= MAX_SAMPLES:
            break
        cell *= 1.5
    pts, normals = project_onto(spline, world[np.sort(first)], iso, 10)
    lo, hi = vol.finite_range
    ok = (np.abs(_values(spline, pts) - iso) <= VALUE_TOL * (hi - lo)) & \
        (np.linalg.norm(normals, axis=1) > 0.5)
    return pts[ok], normals[ok], cell


def sheet_gaps(spline, iso: float, points: np.ndarray, normals: np.ndarray,
               reach: float) -> np.ndarray:
    """Distance from each surface point to the next sheet of ``s = iso`` along its normal.

    The spline is marched from each point along ``+normal`` (towards lower values: the gap to
    a neighbouring sheet) and ``-normal`` (the thickness of the part behind the point) in
    steps of ``GAP_STEP`` grid steps; the first sample on the other side of the isovalue marks
    the next sheet.

    Parameters
    ----------
    spline : Spline
    iso : float
    points : (N, 3) points on the surface
    normals : (N, 3) their unit normals ``-grad s / |grad s|``
    reach : float, farthest distance looked at

    Returns
    -------
    (N,) float64: the smaller of the two distances, ``reach`` where no sheet is that near
    (or the ray leaves the data box first)
    """
    step = float(np.min(spline.volume.spacing))
    ts = np.arange(GAP_START * step, reach + 0.5 * GAP_STEP * step, GAP_STEP * step)
    if len(ts) == 0 or len(points) == 0:
        return np.full(len(points), float(reach))
    fast = compiled(spline)
    if fast is not None:
        # marched point by point, each stopping at its first crossing
        return fast.gaps(points, normals, iso, ts, reach)
    return _sheet_gaps_numpy(spline, iso, points, normals, reach, ts)


def _sheet_gaps_numpy(spline, iso, points, normals, reach, ts):
    """:func:`sheet_gaps` by the vectorised evaluation: all of ``ts (T,)`` at once."""
    gaps = np.full(len(points), float(reach))
    lo = np.array([b[0] for b in spline.bounds])
    hi = np.array([b[1] for b in spline.bounds])
    chunk = max(1, 400_000 // len(ts))
    for start in range(0, len(points), chunk):
        p, nrm = points[start:start + chunk], normals[start:start + chunk]
        for sign in (1.0, -1.0):
            q = p[:, None, :] + sign * ts[None, :, None] * nrm[:, None, :]  # (C, T, 3)
            inside = np.all((q >= lo) & (q <= hi), axis=2)
            f = spline.evaluate(q.reshape(-1, 3)).reshape(inside.shape) - iso
            # along +normal the values fall below iso until the next sheet; along -normal
            # they stay above it until the far side of the part
            crossed = (sign * f >= 0) & inside
            first = np.argmax(crossed, axis=1)
            found = crossed[np.arange(len(p)), first]
            gap = np.where(found, ts[first], reach)
            gaps[start:start + chunk] = np.minimum(gaps[start:start + chunk], gap)
    return gaps


@functools.cache
def _probe_weights(divisions: int) -> np.ndarray:
    """Barycentric weights ``(K, 3)`` of the points of a triangle cut ``divisions`` times
    along each side, its corners left out (they lie on the surface)."""
    i, j = np.meshgrid(np.arange(divisions + 1), np.arange(divisions + 1), indexing="ij")
    keep = i + j <= divisions
    w = np.stack([i[keep], j[keep], divisions - i[keep] - j[keep]], axis=1) / divisions
    return w[~(w == 1.0).any(axis=1)]


def triangles_on_surface(spline, iso: float, triangles: np.ndarray,
                         slack: float = 0.0) -> np.ndarray:
    """Whether triangles with corners on ``s = iso`` lie on one sheet of the surface.

    Each triangle is probed at points at most ``PROBE_SPACING`` grid steps apart; at each the
    first-order distance ``(s - iso) / |grad s|`` to the surface is read. A triangle on the
    surface deviates from it by its sagitta only; one that spans the gap between two sheets
    has probes far from both, and one that passes through a thin part of the object has
    probes well inside and outside it.

    Parameters
    ----------
    spline : Spline
    iso : float
    triangles : (T, 3, 3) corner positions
    slack : float, optional
        Probes this many grid steps from the surface are accepted too.

    Returns
    -------
    (T,) bool: no probe farther than ``SURFACE_DEVIATION`` of the longest side from the
    surface, no probes beyond ``SURFACE_CROSSING`` of it on both sides, and corner normals
    at most ``MAX_CORNER_TURN`` apart
    """
    tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    if len(tri) == 0:
        return np.ones(0, dtype=bool)
    fast = compiled(spline)
    if fast is not None:
        # one compiled call: the front asks about one candidate triangle at a time
        return fast.on_surface(tri, iso, slack, PROBE_SPACING, MAX_PROBE_DIVISIONS,
                               SURFACE_DEVIATION, SURFACE_CROSSING, PROBE_FLOOR, MAX_CORNER_TURN)
    return _on_surface_numpy(spline, iso, tri, slack)


def _on_surface_numpy(spline, iso, tri, slack):
    """:func:`triangles_on_surface` of ``tri (T, 3, 3)`` by the vectorised evaluation."""
    ok = np.ones(len(tri), dtype=bool)
    step = float(np.min(spline.volume.spacing))
    longest = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    divisions = np.clip(np.ceil(longest / (PROBE_SPACING * step)), 2,
                        MAX_PROBE_DIVISIONS).astype(np.int64)
    for k in np.unique(divisions):
        sel = np.flatnonzero(divisions == k)
        w = np.concatenate([np.eye(3), _probe_weights(int(k))])  # corners first
        probes = np.einsum("kc,tcd->tkd", w, tri[sel]).reshape(-1, 3)
        value, grad = spline.value_gradient(probes)
        gn = grad.reshape(len(sel), len(w), 3)[:, :3]
        gn = gn / np.maximum(np.linalg.norm(gn, axis=2, keepdims=True), 1e-300)
        turn = np.minimum(np.minimum(np.einsum("tc,tc->t", gn[:, 0], gn[:, 1]),
                                     np.einsum("tc,tc->t", gn[:, 1], gn[:, 2])),
                          np.einsum("tc,tc->t", gn[:, 2], gn[:, 0]))
        # a vanishing gradient gives an infinite distance: such a probe is not trusted
        dist = (value - iso) / np.maximum(np.linalg.norm(grad, axis=1), 1e-300)
        dist = dist.reshape(len(sel), len(w))[:, 3:]
        floor = PROBE_FLOOR * step
        dev = np.maximum(SURFACE_DEVIATION * longest[sel], max(floor, slack * step))
        cross = np.maximum(SURFACE_CROSSING * longest[sel], floor)
        both_sides = (dist.max(axis=1) > cross) & (dist.min(axis=1) < -cross)
        ok[sel] = (np.abs(dist).max(axis=1) <= dev) & ~both_sides & \
            (turn >= np.cos(MAX_CORNER_TURN))
    return ok


class SplineFront(AdvancingFront):
    """The advancing front with the spline's own test of every triangle.

    The front's tests see the samples and the front near a candidate triangle, not the
    surface between its corners: where two sheets lie close (leaves), a triangle could join a
    vertex of one to an edge of the other. Here a triangle (of a front step or of a filled
    front loop) is accepted only if it lies on one sheet (:func:`triangles_on_surface`), and
    the front seeds every piece of the isosurface (``MAX_SPLINE_SEEDS``), not one object.
    """

    max_seeds = MAX_SPLINE_SEEDS

    def __init__(self, projector, guidance, progress=None):
        super().__init__(projector, guidance, progress)
        #: number of candidate triangles refused for leaving the surface
        self.off_surface = 0
        # the samples are one per grid cell, the edges may be shorter (curved or close
        # sheets): a mesh of equilateral triangles has 2 / (sqrt 3 L^2) vertices per unit area
        per_sample = np.mean(2.0 / np.sqrt(3.0) * (projector.scale / guidance.lengths) ** 2)
        self.vertex_budget = max(VERTEX_BUDGET, VERTEX_SLACK * float(per_sample))

    def _on_surface(self, corners) -> bool:
        if triangles_on_surface(self.proj.spline, self.proj.iso, np.asarray(corners))[0]:
            return True
        self.off_surface += 1
        return False

    def _triangle_ok(self, a, b, v, xv, n, min_angle, existing):
        # the spline probes cost most: they come after the front's own tests
        return super()._triangle_ok(a, b, v, xv, n, min_angle, existing) and \
            self._on_surface((self.P[a], self.P[b], xv))

    def _best_triangulation(self, loop):
        tris = super()._best_triangulation(loop)
        if tris and not triangles_on_surface(self.proj.spline, self.proj.iso,
                                             self.V[np.array(tris)]).all():
            self.off_surface += 1
            return []
        return tris


def _guidance(projector, rho, min_length, max_length):
    k1, k2 = spline_curvatures(projector.spline, projector.points)
    kappa = np.nan_to_num(np.maximum(np.abs(k1), np.abs(k2)), nan=0.0)
    ideal = 2.0 * np.sin(rho / 2.0) / np.maximum(kappa, 1e-300)
    lengths = np.clip(ideal, min_length, max_length)
    # curvature alone allows long edges on flat sheets that lie close together (leaves); the
    # gap bound wins over min_length: a longer edge would join the two sheets
    gaps = sheet_gaps(projector.spline, projector.iso, projector.points, projector.normals,
                      max_length / GAP_FACTOR)
    lengths = np.minimum(lengths, GAP_FACTOR * gaps)
    lengths = limit_gradation(lengths, projector.conn.graph, GRADATION)
    return GuidanceField(lengths, projector.conn.tree)


def border_loops(faces: np.ndarray) -> list[list[int]]:
    """Closed loops of border edges, each as vertex indices in the direction the faces give
    their edges (the open side lies to the right).

    Parameters
    ----------
    faces : (F, 3)

    Returns
    -------
    list of vertex-index lists
    """
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    border = directed[counts[inverse.ravel()] == 1]
    nxt: dict[int, list[int]] = {}
    for a, b in border.tolist():
        nxt.setdefault(a, []).append(b)
    loops, used = [], set()
    for a, b in border.tolist():
        if (a, b) in used:
            continue
        loop, u, v = [], a, b
        while (u, v) not in used:
            used.add((u, v))
            loop.append(u)
            cands = [w for w in nxt.get(v, []) if (v, w) not in used]
            if not cands:
                break
            u, v = v, cands[0]
        if v == a and len(loop) >= 3:
            loops += simple_loops(loop)
    return loops


def _zip(a: list[int], b: list[int]) -> list[list[int]]:
    """Triangles joining the closed ring ``a`` to the closed ring ``b`` inside it (both in the
    same turning direction), walking both by their fraction of a turn."""
    na, nb = len(a), len(b)
    tris, i, j = [], 0, 0
    while i < na or j < nb:
        # advance on the ring whose next vertex comes first along the turn
        if j >= nb or (i < na and (i + 1) / na <= (j + 1) / nb):
            tris.append([a[i % na], a[(i + 1) % na], b[j % nb]])
            i += 1
        else:
            tris.append([a[i % na], b[(j + 1) % nb], b[j % nb]])
            j += 1
    return tris


def true_border(spline, planes, margin: float):
    """The ``keep_open(points)`` test of :func:`fill_holes`: a hole whose rim ``(k, 3)``
    reaches within ``margin`` of the data box, or past a clip plane ``(origin, normal)``,
    is a true border of the surface and stays open."""
    box_lo = np.array([b[0] for b in spline.bounds]) + margin
    box_hi = np.array([b[1] for b in spline.bounds]) - margin

    def keep_open(p):
        if np.any((p <= box_lo) | (p >= box_hi)):
            return True
        return any(np.any((p - o) @ n < 0) for o, n in planes)

    return keep_open


def fill_holes(spline, iso, vertices, faces, keep_open):
    """Close the border loops the front left inside the surface (edges it gave up).

    A loop of 3 vertices becomes a triangle. A larger one is closed by rings: shrunk copies
    of the loop towards its centroid, about one edge length apart, with fewer vertices as
    they shrink, every new vertex moved onto ``s = iso``; ring to ring by a zipper, the last
    ring as a fan around the centroid (no diagonal between loop vertices, which could exist
    already). The flips and relaxation that follow even the rings out.

    Parameters
    ----------
    spline : Spline
    iso : float
    vertices : (V, 3)
    faces : (F, 3)
    keep_open : callable ``(M, 3) points -> bool``: a loop through any such point is a real
        border (the data box, beyond a clip plane) and stays open

    Returns
    -------
    vertices : (V', 3), faces : (F', 3), filled : int number of loops closed
    """
    lo, hi = spline.volume.finite_range
    tol = VALUE_TOL * max(hi - lo, 1e-300)
    new_v, new_f, filled = [], [], 0
    for loop in border_loops(faces):
        pts = vertices[loop]
        if keep_open(pts):
            continue
        rev = loop[::-1]  # the hole's side: the reversed border direction
        if len(loop) == 3:
            new_f.append(rev)
            filled += 1
            continue
        first = len(vertices) + len(new_v)
        loop_v, loop_f = _rings(spline, iso, vertices, rev, first)
        # a hole whose rings do not lie on the surface, or whose triangles leave it (it spans
        # a gap between sheets, e.g. leaves), stays open rather than be closed off the surface
        ring = np.array(loop_v).reshape(-1, 3)
        if len(ring) and np.abs(_values(spline, ring) - iso).max() > tol:
            continue
        allv = np.concatenate([vertices, np.array(new_v).reshape(-1, 3), ring])
        if not triangles_on_surface(spline, iso, allv[np.array(loop_f)], HOLE_SLACK).all():
            continue
        new_v += loop_v
        new_f += loop_f
        filled += 1
    if not filled:
        return vertices, faces, 0
    v = np.concatenate([vertices, np.array(new_v).reshape(-1, 3)])
    return v, np.concatenate([faces, np.array(new_f, dtype=np.int64).reshape(-1, 3)]), filled


def _rings(spline, iso, vertices, rev, first):
    """New vertices (list of (3,)) and triangles closing the loop ``rev`` by rings (see
    :func:`fill_holes`); new vertex indices start at ``first``."""
    new_v, new_f = [], []
    p = vertices[rev]
    centre = p.mean(axis=0)
    edge = float(np.mean(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1)))
    radius = float(np.mean(np.linalg.norm(p - centre, axis=1)))
    n_rings = max(1, int(round(radius / max(edge, 1e-300))))
    outer, k = rev, len(rev)
    for j in range(1, n_rings):
        frac = 1.0 - j / n_rings
        m = max(3, int(round(k * frac)))
        # the ring's vertices sample the loop evenly, pulled towards the centre
        src = p[np.floor(np.arange(m) * k / m).astype(int)]
        ring, _ = project_onto(spline, centre + frac * (src - centre), iso, 10)
        ids = list(range(first + len(new_v), first + len(new_v) + m))
        new_v += list(ring)
        new_f += _zip(outer, ids)
        outer = ids
    c, _ = project_onto(spline, centre[None], iso, 10)
    ci = first + len(new_v)
    new_v.append(c[0])
    new_f += [[outer[i], outer[(i + 1) % len(outer)], ci] for i in range(len(outer))]
    return new_v, new_f


def clip_mesh(spline, iso, vertices, faces, origin, normal, snap_length):
    """Cut a mesh on ``s = iso`` by a plane, keeping the side ``normal`` points to.

    New vertices on the cut lie on the exact section curve (on the plane and on ``s = iso``).

    Parameters
    ----------
    spline : Spline
    iso : float
    vertices : (V, 3)
    faces : (F, 3)
    origin, normal : (3,) the plane
    snap_length : float, vertices closer than this to the plane are moved onto it

    Returns
    -------
    vertices : (V', 3), faces : (F', 3)
    """
    level = sections.Level(spline, iso)
    plane = sections.Plane(origin, normal, float(np.linalg.norm(level.hi - level.lo)))
    limit = sections.STEP_LIMIT * level.step
    v = np.array(vertices, dtype=np.float64, copy=True)
    d = (v - plane.origin) @ plane.normal
    near = np.abs(d) < snap_length
    if near.any():
        moved, ok = sections.project(level, plane, v[near], level.lo, level.hi, limit)
        idx = np.flatnonzero(near)[ok]
        v[idx] = moved[ok]
        d[idx] = 0.0
    side = np.sign(d)
    fs = side[faces]
    keep = faces[(fs >= 0).all(axis=1)]
    cut = faces[(fs > 0).any(axis=1) & (fs < 0).any(axis=1)]
    new_points: list[np.ndarray] = []
    edge_vertex: dict[tuple[int, int], int] = {}

    def on_edge(a, b):
        key = (a, b) if a < b else (b, a)
        if key not in edge_vertex:
            t = d[a] / (d[a] - d[b])
            edge_vertex[key] = len(v) + len(new_points)
            new_points.append(v[a] + t * (v[b] - v[a]))
        return edge_vertex[key]

    tris = []
    for tri in cut:
        poly = []
        for i in range(3):
            a, b = int(tri[i]), int(tri[(i + 1) % 3])
            if d[a] >= 0:
                poly.append(a)
            if d[a] * d[b] < 0:
                poly.append(on_edge(a, b))
        tris += [(poly[0], poly[m], poly[m + 1]) for m in range(1, len(poly) - 1)]
    if new_points:
        moved, _ok = sections.project(level, plane, np.array(new_points), level.lo, level.hi,
                                      limit)
        v = np.concatenate([v, moved])
    f = np.concatenate([keep, np.array(tris, dtype=np.int64).reshape(-1, 3)])
    used = np.unique(f)
    remap = np.full(len(v), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


@contextmanager
def _stage(timings, name):
    """Add the seconds of the enclosed block to ``timings[name]`` (if ``timings`` is a dict)."""
    t0 = time.perf_counter()
    yield
    if timings is not None:
        timings[name] = timings.get(name, 0.0) + time.perf_counter() - t0


def spline_front_mesh(spline, iso: float, planes=(), rho: float = DEFAULT_RHO,
                      min_length: float | None = None, max_length: float | None = None,
                      progress=None, timings: dict | None = None):
    """Triangulate ``s = iso`` with the advancing front on the spline.

    Parameters
    ----------
    spline : Spline
    iso : float
    planes : sequence of (origin (3,), normal (3,))
        Clip planes; the side each normal points to is kept.
    rho : float
        Angle (radians) one edge subtends on the osculating circle: smaller is finer.
    min_length, max_length : float, optional
        Edge-length bounds (default ``DEFAULT_MIN_LENGTH`` / ``DEFAULT_MAX_LENGTH`` grid steps).
        Where two sheets of the surface are closer than ``min_length`` along the normal, edges
        are shorter: ``GAP_FACTOR`` times that distance.
    progress : callable, optional
        ``progress(fraction, message)``; returning False cancels.
    timings : dict, optional
        Receives the seconds of each stage: ``samples``, ``guidance`` (curvatures, sheet gaps,
        gradation), ``front``, ``holes``, ``optimize``, ``finish`` (the last one-sheet test,
        clip planes, normals).

    Returns
    -------
    vertices : (V, 3), faces : (F, 3), normals : (V, 3)
    """
    if not (np.isfinite(rho) and 0 < rho < np.pi):
        raise SplineMeshError(f"rho must be an angle in (0, pi) radians, got {rho}")
    step = float(np.min(spline.volume.spacing))
    lo_len = DEFAULT_MIN_LENGTH * step if min_length is None else float(min_length)
    hi_len = DEFAULT_MAX_LENGTH * step if max_length is None else float(max_length)
    if not 0 < lo_len <= hi_len:
        raise SplineMeshError(f"need 0 < min_length <= max_length, got {lo_len} and {hi_len}")
    with _stage(timings, "samples"):
        pts, nrm, cell = surface_samples(spline, iso)
    planes = [(np.asarray(o, dtype=np.float64), np.asarray(n, dtype=np.float64) /
               np.linalg.norm(n)) for o, n in planes]
    # the front runs two longest edges past each plane so that the cut finds whole triangles
    for origin, normal in planes:
        keep = (pts - origin) @ normal >= -2.0 * hi_len
        pts, nrm = pts[keep], nrm[keep]
    if len(pts) < 3:
        raise SplineMeshError("the clip planes leave no part of the isosurface")
    with _stage(timings, "guidance"):
        proj = SplineProjector(spline, iso, pts, nrm, cell)
        guide = _guidance(proj, rho, lo_len, hi_len)
    with _stage(timings, "front"):
        front = SplineFront(proj, guide, progress)
        vertices, faces = front.run()
    # the front gives up a few edges where its point-cloud tests misjudge the surface (sharp
    # folds); those holes are closed, borders at the data box and past clip planes are not
    keep_open = true_border(spline, planes, 1.5 * cell)
    with _stage(timings, "holes"):
        vertices, faces, _filled = fill_holes(spline, iso, vertices, faces, keep_open)
    # valence flips and tangential relaxation, every moved vertex put back onto the spline
    with _stage(timings, "optimize"):
        vertices, faces, _flips = optimize(vertices, faces, proj, flip_keep=FLIP_KEEP)
    with _stage(timings, "finish"):
        return _finish(spline, iso, vertices, faces, planes, proj.tol,
                       SNAP * float(np.median(guide.lengths)))


def _finish(spline, iso, vertices, faces, planes, tol, snap, one_sheet=True):
    """The last steps of :func:`spline_front_mesh`: drop triangles off the surface (if
    ``one_sheet``), cut by the clip planes, vertices onto the surface, normals."""
    if one_sheet:
        # a flip or a relaxed vertex may still join two sheets: such triangles leave a hole
        # (the closed holes' slack: their triangles passed with it)
        faces = faces[triangles_on_surface(spline, iso, vertices[faces], HOLE_SLACK)]
    used = np.unique(faces)
    remap = np.full(len(vertices), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    vertices, faces = vertices[used], remap[faces]
    for origin, normal in planes:
        vertices, faces = clip_mesh(spline, iso, vertices, faces, origin, normal, snap)
        if len(faces) == 0:
            raise SplineMeshError("the clip planes leave no part of the isosurface")
    # vertices the relaxation or the front left short of the surface (a step limit reached):
    # more Newton steps for those alone
    off = np.abs(_values(spline, vertices) - iso) > tol
    if off.any():
        vertices[off], _ = project_onto(spline, vertices[off], iso, 60, tol)
        # a vertex clamped onto an edge of the data box slides along that edge alone, and
        # the surface need not cross it nearby (2 of 800,000 vertices of the whole bonsai):
        # it goes with its triangles, the border at the box stays open there
        stuck = np.abs(_values(spline, vertices) - iso) > tol
        if stuck.any():
            faces = faces[~stuck[faces].any(axis=1)]
            used = np.unique(faces)
            remap = np.full(len(vertices), -1, dtype=np.int64)
            remap[used] = np.arange(len(used))
            vertices, faces = vertices[used], remap[faces]
    g = spline.gradient(vertices)
    norm = np.linalg.norm(g, axis=1)
    normals = np.divide(-g, norm[:, None], out=np.zeros_like(g), where=norm[:, None] > 0)
    return vertices, faces, normals
