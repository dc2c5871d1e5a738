"""Light post-optimisation of an advancing-front mesh: valence-driven edge flips and tangential
relaxation with re-projection onto the point-set surface.

Conventions: ``vertices (V, 3)`` float64, ``faces (F, 3)`` int, counter-clockwise seen from the
normal side.  Neither step adds or removes vertices, and every vertex moved is put back on the
surface by the same projection (thesis §7.2) that built the mesh, so the mesh stays faithful to
the points.  Border vertices (on edges with one triangle) never move; flips keep the mesh an
oriented manifold (no edge gains a third triangle, no triangle turns over).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse

#: a flip must keep both new triangle normals within this angle of the old ones
FLIP_MAX_TURN = np.deg2rad(30.0)
#: a flip may not lower the pair's smallest radius ratio below this fraction of the old one
FLIP_QUALITY_KEEP = 0.6
#: fraction of the way each interior vertex moves towards its neighbours' centroid
RELAX_STEP = 0.5


def _face_normals(v, f):
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _sub(u, v):
    return (u[0] - v[0], u[1] - v[1], u[2] - v[2])


def _add(u, v):
    return (u[0] + v[0], u[1] + v[1], u[2] + v[2])


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def _norm(u):
    return math.sqrt(_dot(u, u))


def _ratio(pa, pb, pc):
    """2 r_in / r_circ of one triangle from corner tuples (see quality.radius_ratios)."""
    a = _norm(_sub(pb, pc))
    b = _norm(_sub(pc, pa))
    c = _norm(_sub(pa, pb))
    den = a * b * c
    if den <= 0:
        return 0.0
    return max(b + c - a, 0) * max(c + a - b, 0) * max(a + b - c, 0) / den


def border_vertices(n_vertices: int, faces: np.ndarray) -> np.ndarray:
    """``(V,)`` bool: vertices on an edge that has exactly one triangle."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    edges, counts = np.unique(e, axis=0, return_counts=True)
    out = np.zeros(n_vertices, dtype=bool)
    out[edges[counts == 1].ravel()] = True
    return out


def flip_edges(vertices: np.ndarray, faces: np.ndarray, passes: int = 3) -> tuple[np.ndarray, int]:
    """Flip interior edges where that brings the four vertices' valences closer to 6
    (4 on borders), the ideal of a regular triangulation (thesis §7.3: "most vertices have
    degree six").

    Parameters
    ----------
    vertices : (V, 3)
    faces : (F, 3) int

    Returns
    -------
    faces : (F, 3) int, the flipped triangulation
    flips : int, number of flips done
    """
    faces = faces.copy()
    nv = len(vertices)
    P = [tuple(p) for p in vertices.tolist()]  # scalar math on tuples: no per-call overhead
    cos_max = float(np.cos(FLIP_MAX_TURN))
    target = np.where(border_vertices(nv, faces), 4, 6)
    total = 0
    for _ in range(passes):
        half = {}
        for fi, (a, b, c) in enumerate(faces.tolist()):
            half[(a, b)] = fi
            half[(b, c)] = fi
            half[(c, a)] = fi
        undirected = {(min(u, w), max(u, w)) for u, w in half}
        val = np.zeros(nv, dtype=int)
        for u, w in undirected:
            val[u] += 1
            val[w] += 1
        flips = 0
        for (a, b), f1 in list(half.items()):
            if a > b or (b, a) not in half:
                continue
            f2 = half.get((b, a))
            if half.get((a, b)) != f1 or f2 is None or f1 == f2:
                continue
            t1, t2 = faces[f1].tolist(), faces[f2].tolist()
            c = t1[(t1.index(a) + 2) % 3]  # t1 = (a, b, c) cyclically
            d = t2[(t2.index(b) + 2) % 3]  # t2 = (b, a, d) cyclically
            if c == d or (c, d) in half or (d, c) in half:
                continue
            before = sum((val[k] - target[k]) ** 2 for k in (a, b, c, d))
            after = ((val[a] - 1 - target[a]) ** 2 + (val[b] - 1 - target[b]) ** 2
                     + (val[c] + 1 - target[c]) ** 2 + (val[d] + 1 - target[d]) ** 2)
            if after >= before:
                continue
            pa, pb, pc, pd = P[a], P[b], P[c], P[d]
            n_old = _add(_cross(_sub(pb, pa), _sub(pc, pa)), _cross(_sub(pa, pb), _sub(pd, pb)))
            lo = _norm(n_old)
            n1 = _cross(_sub(pd, pa), _sub(pc, pa))
            n2 = _cross(_sub(pb, pd), _sub(pc, pd))
            l1, l2 = _norm(n1), _norm(n2)
            if l1 <= 0 or l2 <= 0 or _dot(n1, n_old) < cos_max * l1 * lo or \
                    _dot(n2, n_old) < cos_max * l2 * lo:
                continue
            q_old = min(_ratio(pa, pb, pc), _ratio(pb, pa, pd))
            q_new = min(_ratio(pa, pd, pc), _ratio(pd, pb, pc))
            if q_new < FLIP_QUALITY_KEEP * q_old:
                continue
            faces[f1] = (a, d, c)
            faces[f2] = (d, b, c)
            for key in ((a, b), (b, a), (b, c), (c, a), (a, d), (d, b)):
                half.pop(key, None)
            half.update({(a, d): f1, (d, c): f1, (c, a): f1, (d, b): f2, (b, c): f2, (c, d): f2})
            val[a] -= 1
            val[b] -= 1
            val[c] += 1
            val[d] += 1
            flips += 1
        total += flips
        if flips == 0:
            break
    return faces, total


def relax(vertices: np.ndarray, faces: np.ndarray, projector, iterations: int = 3) -> np.ndarray:
    """Tangential Laplacian relaxation with re-projection onto the point-set surface.

    Each interior vertex moves ``RELAX_STEP`` of the way to the centroid of its neighbours,
    within its tangent plane, and is projected back (:meth:`Projector.project_with_normals`).
    A move that would turn a triangle over is undone.

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
    _, normals = projector.project_with_normals(v)
    for _ in range(iterations):
        centroid = (adj @ v) / np.maximum(deg, 1)[:, None]
        move = centroid - v
        move -= np.einsum("ij,ij->i", move, normals)[:, None] * normals
        cand = v.copy()
        cand[movable] += RELAX_STEP * move[movable]
        proj, pn = projector.project_with_normals(cand[movable])
        cand[movable] = proj
        # undo moves that turn a triangle over relative to its old orientation
        old_n = _face_normals(v, faces)
        new_n = _face_normals(cand, faces)
        bad_faces = np.einsum("ij,ij->i", old_n, new_n) < 0.5
        if bad_faces.any():
            bad = np.unique(faces[bad_faces])
            cand[bad] = v[bad]
        v = cand
        normals[movable] = pn
    return v


def optimize(vertices: np.ndarray, faces: np.ndarray, projector, rounds: int = 2):
    """Alternate :func:`flip_edges` and :func:`relax`; returns ``(vertices, faces, flips)``."""
    flips = 0
    for _ in range(rounds):
        faces, k = flip_edges(vertices, faces)
        flips += k
        vertices = relax(vertices, faces, projector)
    faces, k = flip_edges(vertices, faces)
    return vertices, faces, flips + k
