"""Light post-optimisation of an advancing-front mesh: valence-driven edge flips and tangential
relaxation with re-projection onto the point-set surface.

Conventions: ``vertices (V, 3)`` float64, ``faces (F, 3)`` int, counter-clockwise seen from the
normal side.  Neither step adds or removes vertices, and every vertex moved is put back on the
surface by the same projection (thesis §7.2) that built the mesh, so the mesh stays faithful to
the points.  Border vertices (on edges with one triangle) never move; flips keep the mesh an
oriented manifold (no edge gains a third triangle, no triangle turns over).
"""

from __future__ import annotations

import numba
import numpy as np
from scipy import sparse

from splineviz.pointcloud.quality import radius_ratios
from splineviz.pointcloud.vec3 import cross, norm, row, sub

#: a flip must keep both new triangle normals within this angle of the old ones
FLIP_MAX_TURN = np.deg2rad(30.0)
#: a flip may not lower the pair's smallest radius ratio below this fraction of the old one
FLIP_QUALITY_KEEP = 0.6
#: fraction of the way each interior vertex moves towards its neighbours' centroid
RELAX_STEP = 0.5
#: a relaxation move may not leave a triangle with a radius ratio below this (unless it was
#: already lower): on a rough surface (Lucy sampled with noise of ~3 spacings) the
#: re-projection of neighbouring moves can fold a triangle into a needle, 7 -> 30 triangles
#: under 0.05 of 17,000, the worst 1e-4
RELAX_MIN_RATIO = 0.2


def face_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Unit normals ``(F, 3)`` of triangles ``f (F, 3)`` over vertices ``v (V, 3)``,
    counter-clockwise."""
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(V, 3)`` of triangles ``(F, 3)`` oriented
    counter-clockwise (zero for a vertex of no triangle)."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])  # 2 x area x unit normal
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def border_vertices(n_vertices: int, faces: np.ndarray) -> np.ndarray:
    """``(V,)`` bool: vertices on an edge that has exactly one triangle."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    # one sorted int64 key per edge: np.unique over rows sorts structured rows, far slower
    key = np.sort(e[:, 0].astype(np.int64) * n_vertices + e[:, 1])
    start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    single = key[start[np.diff(np.r_[start, len(key)]) == 1]]
    out = np.zeros(n_vertices, dtype=bool)
    out[single // n_vertices] = True
    out[single % n_vertices] = True
    return out


@numba.njit(cache=True)
def _nratio(p, i, j, k):
    a = norm(sub(row(p, j), row(p, k)))
    b = norm(sub(row(p, k), row(p, i)))
    c = norm(sub(row(p, i), row(p, j)))
    den = a * b * c
    if den <= 0:
        return 0.0
    return max(b + c - a, 0) * max(c + a - b, 0) * max(a + b - c, 0) / den


@numba.njit(cache=True)
def _flip_pass(p, faces, target, cos_max, keep):
    """One pass of :func:`flip_edges` over the interior edges in face order; flips ``faces``
    in place and returns the number of flips."""
    nv = len(p)
    half = numba.typed.Dict.empty(numba.types.int64, numba.types.int64)  # a * nv + b -> face
    for fi in range(len(faces)):
        for e in range(3):
            half[faces[fi, e] * nv + faces[fi, (e + 1) % 3]] = fi
    val = np.zeros(nv, dtype=np.int64)
    for key in half:
        a, b = key // nv, key % nv
        if a < b or (b * nv + a) not in half:  # each undirected edge once
            val[a] += 1
            val[b] += 1
    snapshot = np.empty((len(half), 2), dtype=np.int64)
    i = 0
    for key, f in half.items():
        snapshot[i, 0], snapshot[i, 1] = key, f
        i += 1
    flips = 0
    for i in range(len(snapshot)):
        key, f1 = snapshot[i, 0], snapshot[i, 1]
        a, b = key // nv, key % nv
        if a > b or (b * nv + a) not in half:
            continue
        if half.get(key, -1) != f1:
            continue
        f2 = half[b * nv + a]
        if f1 == f2:
            continue
        k1 = 0 if faces[f1, 0] == a else (1 if faces[f1, 1] == a else 2)
        c = faces[f1, (k1 + 2) % 3]  # f1 = (a, b, c) cyclically
        k2 = 0 if faces[f2, 0] == b else (1 if faces[f2, 1] == b else 2)
        d = faces[f2, (k2 + 2) % 3]  # f2 = (b, a, d) cyclically
        if c == d or (c * nv + d) in half or (d * nv + c) in half:
            continue
        before = ((val[a] - target[a]) ** 2 + (val[b] - target[b]) ** 2
                  + (val[c] - target[c]) ** 2 + (val[d] - target[d]) ** 2)
        after = ((val[a] - 1 - target[a]) ** 2 + (val[b] - 1 - target[b]) ** 2
                 + (val[c] + 1 - target[c]) ** 2 + (val[d] + 1 - target[d]) ** 2)
        if after >= before:
            continue
        x1 = cross(sub(row(p, b), row(p, a)), sub(row(p, c), row(p, a)))
        x2 = cross(sub(row(p, a), row(p, b)), sub(row(p, d), row(p, b)))
        n_old = (x1[0] + x2[0], x1[1] + x2[1], x1[2] + x2[2])
        lo = norm(n_old)
        n1 = cross(sub(row(p, d), row(p, a)), sub(row(p, c), row(p, a)))
        n2 = cross(sub(row(p, b), row(p, d)), sub(row(p, c), row(p, d)))
        l1, l2 = norm(n1), norm(n2)
        if l1 <= 0 or l2 <= 0:
            continue
        if n1[0] * n_old[0] + n1[1] * n_old[1] + n1[2] * n_old[2] < cos_max * l1 * lo or \
                n2[0] * n_old[0] + n2[1] * n_old[1] + n2[2] * n_old[2] < cos_max * l2 * lo:
            continue
        q_old = min(_nratio(p, a, b, c), _nratio(p, b, a, d))
        q_new = min(_nratio(p, a, d, c), _nratio(p, d, b, c))
        if q_new < keep * q_old:
            continue
        faces[f1, 0], faces[f1, 1], faces[f1, 2] = a, d, c
        faces[f2, 0], faces[f2, 1], faces[f2, 2] = d, b, c
        for u, w in ((a, b), (b, a), (b, c), (c, a), (a, d), (d, b)):
            if (u * nv + w) in half:
                del half[u * nv + w]
        half[a * nv + d] = f1
        half[d * nv + c] = f1
        half[c * nv + a] = f1
        half[d * nv + b] = f2
        half[b * nv + c] = f2
        half[c * nv + d] = f2
        val[a] -= 1
        val[b] -= 1
        val[c] += 1
        val[d] += 1
        flips += 1
    return flips


def flip_edges(vertices: np.ndarray, faces: np.ndarray, passes: int = 3,
               keep: float = FLIP_QUALITY_KEEP) -> tuple[np.ndarray, int]:
    """Flip interior edges where that brings the four vertices' valences closer to 6
    (4 on borders), the ideal of a regular triangulation (thesis §7.3: "most vertices have
    degree six").

    A flip must keep both new triangle normals within ``FLIP_MAX_TURN`` of the pair's old
    normal and the pair's smallest radius ratio above ``keep`` of the old one;
    edges are visited in the order of the faces, each pass on the valences at its start
    updated by its own flips (compiled: the loop over the half edges is sequential).

    Parameters
    ----------
    vertices : (V, 3)
    faces : (F, 3) int
    passes : int, most passes over the edges
    keep : float, smallest accepted ratio of the pair's smallest radius ratio after a flip
        to before (``FLIP_QUALITY_KEEP`` by default)

    Returns
    -------
    faces : (F, 3) int, the flipped triangulation
    flips : int, number of flips done
    """
    out = np.array(faces, dtype=np.int64).reshape(-1, 3)
    p = np.ascontiguousarray(vertices, dtype=np.float64)
    target = np.where(border_vertices(len(p), out), 4, 6).astype(np.int64)
    total = 0
    for _ in range(passes):
        flips = _flip_pass(p, out, target, float(np.cos(FLIP_MAX_TURN)), float(keep))
        total += flips
        if flips == 0:
            break
    return out, total


def relax(vertices: np.ndarray, faces: np.ndarray, projector, iterations: int = 3) -> np.ndarray:
    """Tangential Laplacian relaxation with re-projection onto the point-set surface.

    Each interior vertex moves ``RELAX_STEP`` of the way to the centroid of its neighbours,
    within the tangent plane of the mesh's vertex normal, and is projected back
    (:meth:`Projector.project_with_normals`, with that normal as the hint of its side).  A
    move that would turn a triangle over, or leave it a needle (``RELAX_MIN_RATIO``), is
    undone (:func:`undo_spoiling_moves`).

    Parameters
    ----------
    vertices : (V, 3)
    faces : (F, 3) int
    projector : Projector
    iterations : int

    Returns
    -------
    (V, 3) relaxed vertices.
    """
    v = vertices.copy()
    nv = len(v)
    fixed = border_vertices(nv, faces)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    adj = sparse.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(nv, nv)).tocsr()
    adj = ((adj + adj.T) > 0).astype(float)
    deg = np.asarray(adj.sum(axis=1)).ravel()
    movable = ~fixed & (deg > 0)
    for _ in range(iterations):
        # the tangent plane is the mesh's own, not the surface's at the nearest samples: at a
        # ridge or the rim of a thin part that plane is one side's and holds the direction
        # across the rim, so vertices slid off it and the mesh cut the part short (Lucy's
        # flaps and wing tips: the front's points-to-mesh p99 of 0.338 % of the diagonal
        # became 0.410 % after relaxation, 0.346 % this way); the mesh's normal there
        # bisects the sides, and the move follows the rim
        normals = vertex_normals(v, faces)
        centroid = (adj @ v) / np.maximum(deg, 1)[:, None]
        move = centroid - v
        move -= np.einsum("ij,ij->i", move, normals)[:, None] * normals
        cand = v.copy()
        cand[movable] += RELAX_STEP * move[movable]
        # the normals also tell the side of a thin part a vertex belongs to: without them it
        # is projected onto whichever side's samples are nearest
        cand[movable] = projector.project_with_normals(cand[movable], normals[movable])[0]
        v = undo_spoiling_moves(v, cand, faces, 0.5, RELAX_MIN_RATIO, 1.0)
    return v


def undo_spoiling_moves(old: np.ndarray, new: np.ndarray, faces: np.ndarray, turn_cos: float,
                        floor: float, keep: float) -> np.ndarray:
    """``new`` vertices ``(V, 3)`` with the moves from ``old`` undone, all corners of a
    triangle at once, until no triangle ``(F, 3)`` has turned from its old normal by more
    than ``acos(turn_cos)`` or is left with a radius ratio under ``floor`` and under ``keep``
    times its old one (undoing one triangle's corners can spoil a neighbour: repeated)."""
    # only the triangles of moved vertices can change (often a small share of the mesh)
    faces = faces[np.any(new != old, axis=1)[faces].any(axis=1)]
    before = face_normals(old, faces)
    ratio = radius_ratios(old, faces)
    out = new.copy()
    for _ in range(len(faces)):
        after = radius_ratios(out, faces)
        bad = (np.einsum("ij,ij->i", before, face_normals(out, faces)) < turn_cos) \
            | ((after < floor) & (after < keep * ratio))
        # a triangle with no corner left moved is as it was (a degenerate one stays "turned")
        bad &= np.any(out != old, axis=1)[faces].any(axis=1)
        if not bad.any():
            break
        back = faces[bad].ravel()
        out[back] = old[back]
    return out


def optimize(vertices: np.ndarray, faces: np.ndarray, projector, rounds: int = 2,
             flip_keep: float = FLIP_QUALITY_KEEP):
    """Alternate :func:`flip_edges` (``keep=flip_keep``) and :func:`relax`; returns
    ``(vertices, faces, flips)``."""
    flips = 0
    for _ in range(rounds):
        faces, k = flip_edges(vertices, faces, keep=flip_keep)
        flips += k
        vertices = relax(vertices, faces, projector)
    faces, k = flip_edges(vertices, faces, keep=flip_keep)
    return vertices, faces, flips + k


def compile_kernels() -> None:
    """Compile the flip kernel into numba's on-disk cache (install.sh runs this once)."""
    square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.1], [0.0, 1.0, 0.0]])
    flip_edges(square, np.array([[0, 1, 2], [0, 2, 3]]))
