"""Meshes of spline isosurfaces by flying edges and isotropic remeshing on the spline.

The advancing front (:mod:`.spline_mesh`) asks the spline many small questions one at a time;
its time is far above flying edges' on whole CT volumes. Here every step is a pass over all
vertices or edges at once:

* Start: flying edges (VTK, multithreaded) of spline samples on a grid whose step is
  ``GRID_FRACTION`` of the target edge length: fine enough to catch the surface's features
  narrower than an edge (pits and ridges a coarser grid steps over) and so that no edge of
  the start mesh is longer than ``4/3`` of the target; the vertices are moved onto
  ``s = iso`` by Newton steps along the spline gradient (:func:`.spline_mesh.project_onto`).
* Remeshing (Botsch & Kobbelt's loop with a size field), ``ROUNDS`` rounds of: a target
  length per vertex from the surface's bend at the scale of the edges (:func:`target_lengths`:
  the curvature along each edge from the exact normals at its ends, the length whose chord
  leaves its midpoint ``SIZE_DEVIATION`` of the target off the arc, clamped to ``MIN_SIZE`` of
  it and graded by ``SIZE_GRADING``); edges longer than ``4/3`` of their target split at
  their midpoints' projections (:func:`split_long_edges`); edges shorter than ``4/5`` of it
  collapsed (:func:`collapse_short_edges`, compiled: an independent set per pass, each
  collapse keeping the mesh manifold, no edge longer than ``4/3`` of the target, no triangle
  turned over, and the removed positions within ``COLLAPSE_DEVIATION`` of the target of the
  new triangles, so the features the start caught stay); valence flips (which may lower a
  pair's radius ratio to ``FLIP_KEEP`` of the old one) and tangential relaxation
  (:func:`splineviz.pointcloud.relaxation.optimize`), every moved vertex projected onto the
  spline itself, not onto the start mesh. The splits are woven into the loop, so the flips
  and the relaxation after them regularise the finer mesh where the surface bends. The whole
  bonsai (valence-6 share of interior vertices, with the refinement rounds below): 65.4 ->
  70.8 % (valences 4 / 5 / 7 / 8: 2.3 / 13.3 / 17.2 / 1.4 -> 0.7 / 12.3 / 15.6 / 0.4 %) for
  2.5 % more triangles, mean radius ratio 0.938 -> 0.941; the whole tooth 75.2 -> 79.0 %;
  the leafy 40^3 crop 63.3 -> 69.7 % (its border on the data box, where vertices stay, holds
  most of its valence-7 vertices).
* Refinement: edges whose midpoint still lies more than ``REFINE_DEVIATION`` of the target
  length off the surface (where it bends within an edge of the smallest size, the bonsai's
  leaf rims) are split at the midpoint's projection (:func:`refine_deviating_edges`), so no
  triangle cuts far across a bend, then flips and relaxation regularise the splits' valence-4
  vertices; twice (``REFINE_ROUNDS``). The last flips and relaxation leave a few edges
  deviating again (the leafy crop: 94 of 34,233 interior edges farther than 0.2 edge lengths
  from the surface at their midpoints, 15 farther than 0.3, the largest 0.53; 11, 7 and 0.49
  before the sizing, when a refinement came last; ending with a refinement here costs
  valence-6 share, 69.7 -> 67.5 %).
* One sheet (optional): triangles that leave the surface (flying edges' own, where two sheets
  are about a grid step apart; the front's one-sheet test
  :func:`.spline_mesh.triangles_on_surface`) are dropped and their holes closed on the
  surface (:func:`.spline_mesh.fill_holes`) where rings can; the rest stay open, which costs
  Hausdorff distance (the tooth: 1.4-1.9 grid steps against 0.7 closed), so by default the
  surface stays closed as flying edges' is.
* Finish: clip planes cut exactly, vertices still off the surface get more Newton steps,
  exact normals (the front's own last steps).

Conventions: ``vertices (V, 3)`` float64, ``faces (F, 3)`` int64 counter-clockwise seen from the
normals, ``normals (V, 3)`` unit.
"""

from __future__ import annotations

import numba
import numpy as np

from splineviz.pointcloud import spline_kernels
from splineviz.pointcloud.relaxation import border_vertices, optimize
from splineviz.pointcloud.spline_mesh import (
    DEFAULT_MIN_LENGTH,
    HOLE_SLACK,
    SNAP,
    VALUE_TOL,
    SplineMeshError,
    _finish,
    _stage,
    fill_holes,
    project_onto,
    triangles_on_surface,
    true_border,
)

#: default target edge length in grid steps
DEFAULT_EDGE_LENGTH = 1.0
#: the flying-edges grid step as a share of the target edge length. The whole tooth at one
#: grid step: a sub-voxel pit at (33.9, 69.2, 27.2) that flying edges at 0.81 steps resolve is
#: missed by a start grid at 0.9 (Hausdorff 1.43 steps); 0.6 and 0.5 catch it (0.71 and 0.58
#: with COLLAPSE_DEVIATION 0.25 and 0.15), at 1.3x and 1.5x the time of 0.9
GRID_FRACTION = 0.5
#: edges shorter than this share of the target are collapsed (Botsch & Kobbelt's 4/5)
SHORT = 0.8
#: no collapse makes an edge longer than this share of the target
LONG = 4.0 / 3.0
#: a collapse may turn no triangle's normal further than acos of this
COLLAPSE_KEEP = 0.5
#: a collapse keeps both removed positions within this share of the target length of the
#: triangles around the new vertex: a collapse across a pit or a ridge narrower than an edge
#: (the tooth's sub-voxel pits) would move the mesh that far off the surface
COLLAPSE_DEVIATION = 0.15
#: most valence a collapse may create
MAX_VALENCE = 9
#: rounds of sizing, splits, collapses, flips and relaxation
ROUNDS = 3
#: after the rounds, an edge whose midpoint lies farther than this share of the target length
#: from the surface is split at the midpoint's projection (where the surface bends within an
#: edge). The whole tooth: the largest mesh -> surface distance 0.57 -> 0.28 grid steps for
#: 134 more triangles (of 98,650), radius ratio and valences unchanged
REFINE_DEVIATION = 0.2
#: most passes of that refinement
REFINE_PASSES = 3
#: rounds of the refinement, each followed by flips and relaxation (a split edge's new vertex
#: has valence 4, its opposite corners one more; the flips and relaxation after the last
#: refinement mend them: the leafy 40^3 crop of the bonsai, valence-6 share 67.5 -> 69.7 %
#: for refinement, flips and relaxation, refinement against twice refinement, flips and
#: relaxation)
REFINE_ROUNDS = 2
#: a flip may lower the pair's smallest radius ratio to this share of the old one (the
#: relaxation after it mends the triangles; :data:`~.relaxation.FLIP_QUALITY_KEEP`, 0.6,
#: refuses most flips where the surface bends within an edge). The leafy crop: valence-6
#: share 64.7 / 68.2 / 69.3 / 69.1 % and mean radius ratio 0.933 / 0.925 / 0.923 / 0.921 at
#: 0.6 / 0.3 / 0.15 / 0
FLIP_KEEP = 0.15
#: the chord error the sizing allows, as a share of the target length (:func:`target_lengths`).
#: The leafy crop: 0.05 / 0.1 / 0.2 give 37,587 / 26,261 / 22,299 triangles at valence-6
#: shares 66.8 / 64.7 / 66.8 % (after the loop, flips at 0.6; without sizing 21,537
#: triangles). Sizing by the midpoints' distance to the surface instead of the normals
#: (what the refinement measures): 68.3 against 69.7 % with 840 more triangles
SIZE_DEVIATION = 0.2
#: the smallest target, as a share of the target length (DEFAULT_MIN_LENGTH grid steps at
#: least)
MIN_SIZE = 0.4
#: the target length grows by at most this per unit of distance (the leafy crop, away from
#: the data box: valence-6 share 70.1 / 70.5 / 70.4 % at 0.3 / 0.5 / 1.0, flips at 0.6)
SIZE_GRADING = 0.5
#: spline samples evaluated at once (bounds the memory of the start grid)
SLAB_POINTS = 2_000_000
#: points per task of the parallel Newton projection
PROJECT_CHUNK = 4096


@numba.njit(cache=True, parallel=True)
def _grid_kernel(params, n_work, xs, ys, zs, out):
    """Spline values ``out (nz, ny, nx)`` at the grid ``xs (nx,) x ys (ny,) x zs (nz,)``, one
    z slice per task."""
    for k in numba.prange(zs.shape[0]):
        work = np.empty(n_work)
        res = np.empty(4)
        for j in range(ys.shape[0]):
            for i in range(xs.shape[0]):
                spline_kernels._value_gradient(params, xs[i], ys[j], zs[k], work, res)
                out[k, j, i] = res[0]


@numba.njit(cache=True, parallel=True)
def _project_kernel(params, points, iso, steps, tol, lo, hi, step_limit, n_work, chunk):
    """:func:`splineviz.pointcloud.spline_kernels.project` over chunks of ``points`` on all
    threads."""
    out = np.empty_like(points)
    normals = np.empty_like(points)
    n_chunks = (points.shape[0] + chunk - 1) // chunk
    for c in numba.prange(n_chunks):
        a = c * chunk
        b = min(a + chunk, points.shape[0])
        p, nrm = spline_kernels.project(params, points[a:b], iso, steps, tol, lo, hi,
                                        step_limit, n_work)
        out[a:b] = p
        normals[a:b] = nrm
    return out, normals


def _project(spline, points, iso, steps, tol):
    """Newton projection onto ``s = iso`` (:func:`.spline_mesh.project_onto`), on all cores
    where the compiled kernels cover the model: points ``(M, 3)`` and unit normals ``(M, 3)``."""
    fast = spline_kernels.compiled(spline)
    if fast is None or len(points) < 2 * PROJECT_CHUNK:
        return project_onto(spline, points, iso, steps, tol)
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    return _project_kernel(fast.params, pts, float(iso), int(steps), float(tol), fast.lo,
                           fast.hi, 0.5 * fast.step, fast.n_work, PROJECT_CHUNK)


def _grid_values(spline, step: float):
    """Spline samples on a grid of step ``step`` over the data box (one z slab at a time).

    Returns
    -------
    values : (nz, ny, nx), origin : (3,), spacing : (3,)
    """
    lo = np.array([b[0] for b in spline.bounds], dtype=np.float64)
    hi = np.array([b[1] for b in spline.bounds], dtype=np.float64)
    dims = np.maximum(np.ceil((hi - lo) / step).astype(int), 1) + 1
    spacing = (hi - lo) / (dims - 1)
    x, y, z = (lo[d] + spacing[d] * np.arange(dims[d]) for d in range(3))
    fast = spline_kernels.compiled(spline)
    if fast is not None:
        values = np.empty((dims[2], dims[1], dims[0]))
        _grid_kernel(fast.params, fast.n_work, x, y, z, values)
        return values, lo, spacing
    xx, yy = np.meshgrid(x, y)  # (ny, nx): VTK's point order, x fastest
    plane = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)
    values = np.empty((dims[2], dims[1] * dims[0]))
    per = max(1, SLAB_POINTS // len(plane))
    for k0 in range(0, dims[2], per):
        ks = np.arange(k0, min(k0 + per, dims[2]))
        pts = np.tile(plane, (len(ks), 1))
        pts[:, 2] = np.repeat(z[ks], len(plane))
        values[ks] = spline.evaluate(pts).reshape(len(ks), -1)
    return values.reshape(dims[2], dims[1], dims[0]), lo, spacing


def flying_edges_start(spline, iso: float, step: float):
    """Flying-edges mesh of spline samples on a grid of step ``step``, vertices projected onto
    ``s = iso``.

    Returns
    -------
    vertices : (V, 3), faces : (F, 3)
    """
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D

    values, origin, spacing = _grid_values(spline, step)
    image = vtkImageData()
    image.SetDimensions(values.shape[2], values.shape[1], values.shape[0])
    image.SetOrigin(*origin)
    image.SetSpacing(*spacing)
    image.GetPointData().SetScalars(numpy_to_vtk(values.ravel(), deep=True))
    fe = vtkFlyingEdges3D()
    fe.SetInputData(image)
    fe.SetValue(0, iso)
    fe.ComputeNormalsOff()
    fe.ComputeGradientsOff()
    fe.ComputeScalarsOff()
    fe.Update()
    out = fe.GetOutput()
    if out.GetNumberOfPoints() == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    v = vtk_to_numpy(out.GetPoints().GetData()).astype(np.float64)
    f = vtk_to_numpy(out.GetPolys().GetConnectivityArray()).astype(np.int64).reshape(-1, 3)
    # a grid corner exactly at the isovalue is a vertex of each of its edges: one vertex,
    # and the triangles between those copies go
    v, inverse = np.unique(v, axis=0, return_inverse=True)
    f = inverse.reshape(-1)[f]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])]
    return _compact(v, f)


def _adjacency(n: int, faces: np.ndarray):
    """CSR vertex -> neighbours and vertex -> faces of a triangle mesh."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = np.concatenate([e, e[:, ::-1]])
    key = np.sort(e[:, 0] * n + e[:, 1])
    key = key[np.r_[True, key[1:] != key[:-1]]]
    vv_idx = (key % n).astype(np.int64)
    vv_ptr = np.searchsorted(key // n, np.arange(n + 1)).astype(np.int64)
    fv = faces.ravel()
    order = np.argsort(fv, kind="stable")
    vf_idx = (order // 3).astype(np.int64)
    vf_ptr = np.searchsorted(fv[order], np.arange(n + 1)).astype(np.int64)
    return vv_ptr, vv_idx, vf_ptr, vf_idx


@numba.njit(cache=True)
def _normal(p, q, r):
    ux, uy, uz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    wx, wy, wz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    nx, ny, nz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
    s = np.sqrt(nx * nx + ny * ny + nz * nz)
    if s == 0.0:
        return 0.0, 0.0, 0.0
    return nx / s, ny / s, nz / s


@numba.njit(cache=True)
def _point_triangle_distance2(p, a, b, c):
    """Squared distance of the point ``p`` to the triangle ``(a, b, c)`` (closest point by
    its Voronoi regions, Ericson's "Real-Time Collision Detection" §5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0.0 and d2 <= 0.0:
        q = a
    else:
        bp = p - b
        d3, d4 = ab @ bp, ac @ bp
        cp = p - c
        d5, d6 = ab @ cp, ac @ cp
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0.0 and d4 <= d3:
            q = b
        elif d6 >= 0.0 and d5 <= d6:
            q = c
        elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            q = a + d1 / (d1 - d3) * ab
        elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            q = a + d2 / (d2 - d6) * ac
        elif va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
            q = b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
        else:
            den = va + vb + vc
            q = a + (vb / den) * ab + (vc / den) * ac
    d = p - q
    return d @ d


@numba.njit(cache=True)
def _fan_distance2(p, m, a, b, v, faces, vf_ptr, vf_idx):
    """Squared distance of ``p`` to the triangles around ``a`` and ``b`` once the edge
    ``(a, b)`` is collapsed onto ``m`` (the two triangles of the edge gone)."""
    best = np.inf
    for end in (a, b):
        for i in range(vf_ptr[end], vf_ptr[end + 1]):
            f = vf_idx[i]
            p0, p1, p2 = faces[f, 0], faces[f, 1], faces[f, 2]
            if (p0 == a or p1 == a or p2 == a) and (p0 == b or p1 == b or p2 == b):
                continue
            x = m if p0 == end else v[p0]
            y = m if p1 == end else v[p1]
            z = m if p2 == end else v[p2]
            best = min(best, _point_triangle_distance2(p, x, y, z))
    return best


@numba.njit(cache=True)
def _collapse_pass(v, faces, alive, ea, eb, vv_ptr, vv_idx, vf_ptr, vf_idx, fixed, size,
                   long2, keep, max_valence, deviation2, moved):
    """Collapse the edges ``(ea[k], eb[k])`` (shortest first) onto their midpoints where the
    mesh stays manifold, no edge at the midpoint is longer than ``sqrt(long2)`` times the
    edge's target ``(size[a] + size[b]) / 2`` (``size (V,)``: target lengths per vertex) and
    both ends stay within ``sqrt(deviation2)`` times that target of the triangles around the
    midpoint; the kept end takes the smaller target. The 1-rings of both ends are locked for
    the rest of the pass, so the adjacency read from the CSR arrays stays valid. Returns the
    number of collapses."""
    n = v.shape[0]
    locked = np.zeros(n, dtype=np.bool_)
    m = np.empty(3)
    count = 0
    for k in range(ea.shape[0]):
        a, b = ea[k], eb[k]
        if locked[a] or locked[b] or fixed[a] or fixed[b]:
            continue
        # link condition of an interior edge: exactly the two opposite vertices in common,
        # each keeping valence >= 3
        common = 0
        thin = False
        for i in range(vv_ptr[a], vv_ptr[a + 1]):
            x = vv_idx[i]
            for j in range(vv_ptr[b], vv_ptr[b + 1]):
                if vv_idx[j] == x:
                    common += 1
                    if vv_ptr[x + 1] - vv_ptr[x] <= 3:
                        thin = True
        if common != 2 or thin:
            continue
        if (vv_ptr[a + 1] - vv_ptr[a]) + (vv_ptr[b + 1] - vv_ptr[b]) - 4 > max_valence:
            continue
        for c in range(3):
            m[c] = 0.5 * (v[a, c] + v[b, c])
        target2 = (0.5 * (size[a] + size[b])) ** 2
        ok = True
        for end in (a, b):
            for i in range(vv_ptr[end], vv_ptr[end + 1]):
                x = vv_idx[i]
                d0, d1, d2 = v[x, 0] - m[0], v[x, 1] - m[1], v[x, 2] - m[2]
                if x != a and x != b and d0 * d0 + d1 * d1 + d2 * d2 > long2 * target2:
                    ok = False
            # no surviving triangle turned over
            for i in range(vf_ptr[end], vf_ptr[end + 1]):
                f = vf_idx[i]
                p, q, r = faces[f, 0], faces[f, 1], faces[f, 2]
                if (p == a or q == a or r == a) and (p == b or q == b or r == b):
                    continue
                o0, o1, o2 = _normal(v[p], v[q], v[r])
                pp = m if p == end else v[p]
                qq = m if q == end else v[q]
                rr = m if r == end else v[r]
                n0, n1, n2 = _normal(pp, qq, rr)
                if o0 * n0 + o1 * n1 + o2 * n2 < keep:
                    ok = False
        if not ok:
            continue
        if (_fan_distance2(v[a], m, a, b, v, faces, vf_ptr, vf_idx) > deviation2 * target2
                or _fan_distance2(v[b], m, a, b, v, faces, vf_ptr, vf_idx)
                > deviation2 * target2):
            continue
        for c in range(3):
            v[a, c] = m[c]
        size[a] = min(size[a], size[b])
        moved[a] = True
        for i in range(vf_ptr[b], vf_ptr[b + 1]):
            f = vf_idx[i]
            if faces[f, 0] == a or faces[f, 1] == a or faces[f, 2] == a:
                alive[f] = False
            for c in range(3):
                if faces[f, c] == b:
                    faces[f, c] = a
        for end in (a, b):
            locked[end] = True
            for i in range(vv_ptr[end], vv_ptr[end + 1]):
                locked[vv_idx[i]] = True
        count += 1
    return count


def _compact(vertices, faces):
    """The vertices some face uses, and the faces renumbered."""
    used = np.flatnonzero(np.bincount(faces.ravel(), minlength=len(vertices)))
    remap = np.full(len(vertices), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return vertices[used], remap[faces]


def collapse_short_edges(spline, iso, vertices, faces, length, tol: float,
                         passes: int = 8, return_sizes: bool = False):
    """Collapse edges shorter than ``SHORT`` times their target length onto their midpoints,
    projected onto ``s = iso``; border vertices (the data box) stay.

    Parameters
    ----------
    spline : Spline
    iso : float
    vertices : (V, 3) on the surface
    faces : (F, 3)
    length : float or (V,)
        Target edge length, or one per vertex (an edge's target: the mean of its ends').
    tol : float, Newton tolerance on |s - iso|
    passes : int, most passes (each one an independent set of collapses)
    return_sizes : bool
        Also return the per-vertex targets of the kept vertices (a collapse keeps the
        smaller of its ends').

    Returns
    -------
    vertices : (V', 3), faces : (F', 3), collapses : int[, sizes : (V',)]
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64).copy()
    f = np.ascontiguousarray(faces, dtype=np.int64).copy()
    size = np.ascontiguousarray(np.broadcast_to(np.asarray(length, dtype=np.float64),
                                                (len(v),))).copy()
    total = 0
    for _ in range(passes):
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        e = e[e[:, 0] < e[:, 1]]  # each interior edge once (the other side has it reversed)
        d2 = np.einsum("ij,ij->i", v[e[:, 0]] - v[e[:, 1]], v[e[:, 0]] - v[e[:, 1]])
        short = d2 < (SHORT * 0.5 * (size[e[:, 0]] + size[e[:, 1]])) ** 2
        if not short.any():
            break
        e, d2 = e[short], d2[short]
        e = e[np.argsort(d2, kind="stable")]
        vv_ptr, vv_idx, vf_ptr, vf_idx = _adjacency(len(v), f)
        fixed = border_vertices(len(v), f)
        alive = np.ones(len(f), dtype=np.bool_)
        moved = np.zeros(len(v), dtype=np.bool_)
        k = _collapse_pass(v, f, alive, np.ascontiguousarray(e[:, 0]),
                           np.ascontiguousarray(e[:, 1]), vv_ptr, vv_idx, vf_ptr, vf_idx,
                           fixed, size, LONG ** 2, COLLAPSE_KEEP, MAX_VALENCE,
                           COLLAPSE_DEVIATION ** 2, moved)
        f = f[alive]
        if moved.any():
            v[moved], _n = _project(spline, v[moved], iso, 30, tol)
        total += k
        if k == 0:
            break
    used = np.flatnonzero(np.bincount(f.ravel(), minlength=len(v)))
    v, f = _compact(v, f)
    if return_sizes:
        return v, f, total, size[used]
    return v, f, total


def _split_marked(faces, edge_of_face, new_vertex):
    """Faces with the marked edges split (red-green refinement): a face with one marked edge
    in two, two in three, three in four, counter-clockwise kept.

    Parameters
    ----------
    faces : (F, 3)
    edge_of_face : (F, 3) edge ids of the face's edges (v0 v1, v1 v2, v2 v0)
    new_vertex : (E,) the vertex put on each edge, -1 where the edge is not split

    Returns
    -------
    (F', 3) faces
    """
    m = new_vertex[edge_of_face]  # (F, 3)
    count = (m >= 0).sum(axis=1)
    out = [faces[count == 0]]
    for r in range(3):
        i, j, k = faces[:, r], faces[:, (r + 1) % 3], faces[:, (r + 2) % 3]
        x, y = m[:, r], m[:, (r + 1) % 3]
        one = (count == 1) & (x >= 0)  # the edge (i, j) split at x
        out += [np.stack([i[one], x[one], k[one]], 1), np.stack([x[one], j[one], k[one]], 1)]
        two = (count == 2) & (m[:, (r + 2) % 3] < 0)  # (i, j) at x and (j, k) at y
        out += [np.stack([x[two], j[two], y[two]], 1), np.stack([i[two], x[two], y[two]], 1),
                np.stack([i[two], y[two], k[two]], 1)]
    three = count == 3
    a, b, c = faces[three].T
    x, y, z = m[three].T
    out += [np.stack([a, x, z], 1), np.stack([x, b, y], 1), np.stack([z, y, c], 1),
            np.stack([x, y, z], 1)]
    return np.concatenate(out)


def refine_deviating_edges(spline, iso, vertices, faces, deviation: float, tol: float,
                           passes: int = REFINE_PASSES):
    """Split the interior edges whose midpoint lies farther than ``deviation`` from the
    surface at the midpoint's projection onto ``s = iso`` (border edges stay: their new
    vertices would leave the data box's faces).

    Parameters
    ----------
    spline : Spline
    iso : float
    vertices : (V, 3) on the surface
    faces : (F, 3)
    deviation : float, world units
    tol : float, Newton tolerance on |s - iso|
    passes : int, most passes (each splits the edges still deviating)

    Returns
    -------
    vertices : (V', 3), faces : (F', 3), splits : int
    """
    v, f = vertices, faces
    total = 0
    for _ in range(passes):
        a, b, edge_id, counts = _edges(v, f)
        mid = 0.5 * (v[a] + v[b])
        proj, _n = _project(spline, mid, iso, 30, tol)
        split = (np.linalg.norm(proj - mid, axis=1) > deviation) & (counts == 2)
        if not split.any():
            break
        v, f = _split_at(v, f, edge_id, split, proj[split])
        total += int(split.sum())
    return v, f, total


def _edges(vertices, faces):
    """The mesh's edges: ends ``a (E,)``, ``b (E,)`` (``a < b``), each face corner's edge id
    ``edge_id (3F,)`` (the edges v0 v1, v1 v2, v2 v0 of all faces in turn) and the faces per
    edge ``counts (E,)``."""
    n = len(vertices)
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    key = e[:, 0].astype(np.int64) * n + e[:, 1]
    uniq, edge_id, counts = np.unique(key, return_inverse=True, return_counts=True)
    return uniq // n, uniq % n, edge_id, counts


def _split_at(vertices, faces, edge_id, split, points):
    """The mesh with the edges ``split (E,)`` bool split at ``points (S, 3)``, one per split
    edge in order (:func:`_split_marked`)."""
    new_vertex = np.full(len(split), -1, dtype=np.int64)
    new_vertex[split] = len(vertices) + np.arange(int(split.sum()))
    return (np.concatenate([vertices, points]),
            _split_marked(faces, edge_id.reshape(3, -1).T, new_vertex))


def _unit_gradients(spline, points):
    """Unit spline gradients ``(N, 3)`` at ``points (N, 3)`` (zero where the gradient is)."""
    fast = spline_kernels.compiled(spline)
    g = fast.value_gradient(points)[1] if fast is not None else spline.gradient(points)
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    return np.divide(g, norm, out=np.zeros_like(g), where=norm > 0)


def target_lengths(spline, vertices, faces, length: float, deviation: float,
                   min_length: float, grading: float = None):
    """Per-vertex target edge lengths from the surface's bend at the scale of the edges.

    An edge ``(a, b)`` turns the exact normals (spline gradients) by ``|n_a - n_b|`` over
    ``|a - b|``: the curvature along it, ``kappa`` (chord estimate ``2 sin(theta/2) / l``,
    exact on a circle). A chord of length ``L`` on a circle of curvature ``kappa`` leaves its
    midpoint ``kappa L^2 / 8`` off the arc, so the target ``sqrt(8 deviation / kappa)`` keeps
    that within ``deviation``; a vertex takes the largest curvature of its edges, clamped to
    ``[min_length, length]``, and the field is smoothed so that it grows by at most
    ``grading`` per unit of distance (a sudden change of size costs irregular vertices).

    Parameters
    ----------
    spline : Spline
    vertices : (V, 3) on the surface
    faces : (F, 3)
    length : float, the target where the surface is flat
    deviation : float, world units
    min_length : float
    grading : float, optional (default ``SIZE_GRADING``)

    Returns
    -------
    (V,) target lengths
    """
    grading = SIZE_GRADING if grading is None else grading
    n = _unit_gradients(spline, vertices)
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    e = np.unique(e[:, 0].astype(np.int64) * len(vertices) + e[:, 1])
    a, b = e // len(vertices), e % len(vertices)
    d = np.linalg.norm(vertices[a] - vertices[b], axis=1)
    kappa = np.linalg.norm(n[a] - n[b], axis=1) / np.maximum(d, 1e-300)
    k = np.zeros(len(vertices))
    np.maximum.at(k, a, kappa)
    np.maximum.at(k, b, kappa)
    size = np.clip(np.sqrt(8.0 * deviation / np.maximum(k, 1e-300)), min_length, length)
    # each pass lowers a target to its neighbours' plus the grading; a few passes until no
    # target changes (the change travels (length - min_length) / grading, a few edges)
    while True:
        smaller = size.copy()
        np.minimum.at(smaller, a, size[b] + grading * d)
        np.minimum.at(smaller, b, size[a] + grading * d)
        if np.array_equal(smaller, size):
            break
        size = smaller
    return size


def split_long_edges(spline, iso, vertices, faces, size, tol: float):
    """Split the interior edges longer than ``LONG`` times their target (the mean of their
    ends' ``size``) at their midpoints' projections onto ``s = iso`` (red-green, as
    :func:`refine_deviating_edges`; border edges stay on the data box).

    Parameters
    ----------
    spline : Spline
    iso : float
    vertices : (V, 3) on the surface
    faces : (F, 3)
    size : (V,) target lengths
    tol : float, Newton tolerance on |s - iso|

    Returns
    -------
    vertices : (V', 3), faces : (F', 3), sizes : (V',) (a new vertex: its edge's target),
    splits : int
    """
    v, f = vertices, faces
    a, b, edge_id, counts = _edges(v, f)
    target = 0.5 * (size[a] + size[b])
    split = (np.linalg.norm(v[a] - v[b], axis=1) > LONG * target) & (counts == 2)
    if not split.any():
        return v, f, size, 0
    proj, _n = _project(spline, 0.5 * (v[a[split]] + v[b[split]]), iso, 30, tol)
    v, f = _split_at(v, f, edge_id, split, proj)
    return v, f, np.concatenate([size, target[split]]), int(split.sum())


class _SplineSurface:
    """The projector :func:`splineviz.pointcloud.relaxation.relax` asks: Newton steps onto
    ``s = iso``."""

    def __init__(self, spline, iso, tol):
        self.spline, self.iso, self.tol = spline, float(iso), tol

    def project_with_normals(self, points, normal_hint=None):
        return _project(self.spline, points, self.iso, 30, self.tol)

    def project(self, points):
        return self.project_with_normals(points)[0]


def spline_remesh(spline, iso: float, planes=(), edge_length: float | None = None,
                  rounds: int = ROUNDS, one_sheet: bool = False, progress=None,
                  timings: dict | None = None):
    """Triangulate ``s = iso`` by flying edges and isotropic remeshing on the spline.

    Parameters
    ----------
    spline : Spline
    iso : float
    planes : sequence of (origin (3,), normal (3,))
        Clip planes; the side each normal points to is kept.
    edge_length : float, optional
        Target edge length (default ``DEFAULT_EDGE_LENGTH`` grid steps, at least
        ``DEFAULT_MIN_LENGTH`` of one).
    rounds : int, rounds of sizing, splits, collapses, flips and relaxation
    one_sheet : bool
        Drop the triangles that leave the surface by the front's one-sheet test (flying
        edges' own where two sheets are about a grid step apart, as on thin leaves) and close
        their holes where rings on the surface can (else they stay open). Off (default): the
        surface stays closed as flying edges' is, such triangles bridging the sheets.
    progress : callable, optional
        ``progress(fraction, message)``; returning False cancels (raises
        :class:`~splineviz.pointcloud.spline_mesh.SplineMeshError`).
    timings : dict, optional
        Receives the seconds of the stages ``start`` (samples, flying edges, projection),
        ``remesh``, ``holes`` (``one_sheet`` only) and ``finish``.

    Returns
    -------
    vertices : (V, 3), faces : (F, 3), normals : (V, 3)
    """
    step = float(np.min(spline.volume.spacing))
    length = DEFAULT_EDGE_LENGTH * step if edge_length is None else float(edge_length)
    if not (np.isfinite(length) and length >= DEFAULT_MIN_LENGTH * step):
        raise SplineMeshError(f"edge_length must be at least {DEFAULT_MIN_LENGTH * step:g} "
                              f"({DEFAULT_MIN_LENGTH:g} grid steps), got {edge_length}")
    lo, hi = spline.volume.finite_range
    tol = VALUE_TOL * max(hi - lo, 1e-300)
    planes = [(np.asarray(o, dtype=np.float64), np.asarray(n, dtype=np.float64) /
               np.linalg.norm(n)) for o, n in planes]

    def report(fraction, message):
        if progress is not None and progress(fraction, message) is False:
            raise SplineMeshError("meshing cancelled")

    report(0.0, "sampling the spline")
    with _stage(timings, "start"):
        v, f = flying_edges_start(spline, iso, GRID_FRACTION * length)
        if len(f) == 0:
            raise SplineMeshError(f"the isovalue {iso:g} is not crossed by the spline")
        # the remeshing runs one edge past each plane so that the cut finds whole triangles
        for origin, normal in planes:
            f = f[((v[f] - origin) @ normal >= -2.0 * length).any(axis=1)]
        if len(f) == 0:
            raise SplineMeshError("the clip planes leave no part of the isosurface")
        v, f = _compact(v, f)
        v, _n = _project(spline, v, iso, 30, tol)
    surface = _SplineSurface(spline, iso, tol)
    with _stage(timings, "remesh"):
        for r in range(rounds):
            report(0.1 + 0.8 * r / rounds, f"remeshing (round {r + 1} of {rounds})")
            size = target_lengths(spline, v, f, length, SIZE_DEVIATION * length,
                                  max(DEFAULT_MIN_LENGTH * step, MIN_SIZE * length))
            v, f, size, _splits = split_long_edges(spline, iso, v, f, size, tol)
            v, f, _k = collapse_short_edges(spline, iso, v, f, size, tol)
            v, f, _flips = optimize(v, f, surface, rounds=1, flip_keep=FLIP_KEEP)
        for _ in range(REFINE_ROUNDS):
            v, f, _splits = refine_deviating_edges(spline, iso, v, f,
                                                   REFINE_DEVIATION * length, tol)
            v, f, _flips = optimize(v, f, surface, rounds=1, flip_keep=FLIP_KEEP)
    if one_sheet:
        report(0.85, "closing holes")
        with _stage(timings, "holes"):
            # flying edges' own triangles can leave the surface where two sheets are about a
            # grid step apart (the front's one-sheet test): they go, and their holes are
            # closed on the surface as the front's are where the rings stay on it; borders at
            # the data box and past the planes stay open
            v, f = _compact(v, f[triangles_on_surface(spline, iso, v[f], HOLE_SLACK)])
            v, f, _filled = fill_holes(spline, iso, v, f,
                                       true_border(spline, planes, 1.5 * step))
            v, f, _flips = optimize(v, f, surface, rounds=1)
    report(0.9, "finishing")
    with _stage(timings, "finish"):
        out = _finish(spline, iso, v, f, planes, tol, SNAP * length, one_sheet)
    report(1.0, "done")
    return out
