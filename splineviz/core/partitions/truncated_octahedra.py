"""The truncated-octahedral partition and its 144-tetrahedra split (thesis §5.2-5.3).

Everything is in *index space* (grid spacing h = 1). Data points are the integer points. The
truncated octahedra (TOs) have radius h = 1 and are centred at the BCC lattice

    L = {(i + 1/2, j + 1/2, k + 1/2) : i, j, k all even or all odd},

i.e. they are the Voronoi cells of L. A TO centred at the origin has the 24 vertices
"all permutations of (0, +-1/2, +-1)", 6 square faces on the planes |x_a| = 1 and 8 hexagonal
faces on the planes s.x = 3/2, s in {+-1}^3; its 8 data points are the hexagon centres
s/2 (Fig. 5.1). Each TO is split into 144 tetrahedra [v0, v1, v2, v3]: v0 the TO centre, v1 a
face centre, v2 the midpoint of an edge of that face, v3 an end of that edge. Tetrahedra over a
square face form the class T^S (48), over a hexagon T^H (96).

All TOs are translates of the reference TO at the origin by lattice vectors, so the generic
tables here (vertices, barycentric matrices, neighbours) are computed once, from the
definitions above.
"""

from __future__ import annotations

from functools import cache
from itertools import permutations, product

import numpy as np

from splineviz.core import bform

#: tolerance for geometric coincidence tests in index units
EPS = 1e-9

#: the 6 square-face and 8 hexagonal-face neighbour offsets of a TO (lattice vectors)
SQUARE_NEIGHBOURS = np.array(
    [s * e for e in np.eye(3) for s in (1.0, -1.0)]
) * 2.0
HEX_NEIGHBOURS = np.array(list(product((1.0, -1.0), repeat=3)))
NEIGHBOUR_OFFSETS = np.concatenate([SQUARE_NEIGHBOURS, HEX_NEIGHBOURS])  # (14, 3)

#: the data points of the reference TO: centres of its hexagonal faces
DATA_OFFSETS = HEX_NEIGHBOURS / 2.0  # (8, 3)


@cache
def to_vertices() -> np.ndarray:
    """(24, 3) vertices of the reference TO: permutations of (0, +-1/2, +-1)."""
    pts = set()
    for a, b in product((0.5, -0.5), (1.0, -1.0)):
        for perm in permutations((0.0, a, b)):
            pts.add(perm)
    out = np.array(sorted(pts))
    out.flags.writeable = False
    return out


@cache
def faces():
    """The 14 faces of the reference TO.

    Returns
    -------
    list of dict with keys ``normal`` (3,), ``offset`` (plane ``normal . x = offset``),
    ``kind`` ("S" square or "H" hexagon), ``centre`` (3,) and ``loop`` (n, 3) vertices in
    cyclic order (n = 4 or 6). Squares come first.
    """
    verts = to_vertices()
    out = []
    planes = [(n, 1.0, "S") for n in SQUARE_NEIGHBOURS / 2.0] + [
        (n, 1.5, "H") for n in HEX_NEIGHBOURS
    ]
    for normal, offset, kind in planes:
        on = verts[np.abs(verts @ normal - offset) < EPS]
        centre = on.mean(axis=0)
        # cyclic order by angle in the face plane
        u = on[0] - centre
        w = np.cross(normal, u)
        ang = np.arctan2((on - centre) @ w, (on - centre) @ u)
        out.append(
            dict(normal=normal, offset=offset, kind=kind, centre=centre, loop=on[np.argsort(ang)])
        )
    return out


@cache
def generic_tetrahedra():
    """The 144 generic tetrahedra of the reference TO.

    Returns
    -------
    vertices : (144, 4, 3) [v0, v1, v2, v3] = [centre, face centre, edge midpoint, vertex]
    kind : (144,) array of "S" / "H"
    face : (144,) index into :func:`faces`
    """
    tets, kinds, face_ids = [], [], []
    for f, face in enumerate(faces()):
        loop = face["loop"]
        for e in range(len(loop)):
            a, b = loop[e], loop[(e + 1) % len(loop)]
            mid = (a + b) / 2.0
            for v3 in (a, b):
                tets.append([np.zeros(3), face["centre"], mid, v3])
                kinds.append(face["kind"])
                face_ids.append(f)
    verts = np.array(tets)
    for arr in (verts,):
        arr.flags.writeable = False
    return verts, np.array(kinds), np.array(face_ids)


@cache
def barycentric_matrices() -> np.ndarray:
    """(144, 4, 4) M_T^{-1} of the generic tetrahedra (index space, TO centred at 0)."""
    m = bform.barycentric_matrix(generic_tetrahedra()[0])
    m.flags.writeable = False
    return m


@cache
def _face_sectors():
    """Per face: an in-plane frame and the generic tetrahedron of each angular sector.

    The faces are regular polygons and their tetrahedra are the fan triangles (centre, edge
    midpoint, vertex), each spanning pi/n_edges of angle measured from the first loop vertex;
    so a point's tetrahedron follows from the angle of its projection on the face plane.

    Returns
    -------
    frames : (14, 2, 3) unit vectors u, w spanning each face plane
    sectors : (14, 12) generic tetrahedron per sector (squares use the first 8)
    n_sectors : (14,) 8 or 12
    """
    verts, _, face_of = generic_tetrahedra()
    frames = np.empty((14, 2, 3))
    sectors = np.zeros((14, 12), dtype=np.int64)
    n_sectors = np.empty(14, dtype=np.int64)
    for f, face in enumerate(faces()):
        u = face["loop"][0] - face["centre"]
        u /= np.linalg.norm(u)
        w = np.cross(face["normal"] / np.linalg.norm(face["normal"]), u)
        frames[f] = u, w
        n = 2 * len(face["loop"])
        n_sectors[f] = n
        for t in np.flatnonzero(face_of == f):
            mid = verts[t, 1:].mean(axis=0) - face["centre"]  # centroid of [v1, v2, v3]
            ang = np.arctan2(mid @ w, mid @ u) % (2 * np.pi)
            sectors[f, int(ang // (2 * np.pi / n))] = t
    return frames, sectors, n_sectors


def nearest_centre(points: np.ndarray) -> np.ndarray:
    """Centre of the TO containing each point (its nearest BCC lattice point).

    Parameters
    ----------
    points : (N, 3) index-space points

    Returns
    -------
    (N, 3) float64 centres (half-integer coordinates)
    """
    p = np.asarray(points, dtype=np.float64)
    ca = 0.5 + 2.0 * np.round((p - 0.5) / 2.0)
    cb = 1.5 + 2.0 * np.round((p - 1.5) / 2.0)
    da = np.sum((p - ca) ** 2, axis=1)
    db = np.sum((p - cb) ** 2, axis=1)
    return np.where((da <= db)[:, None], ca, cb)


def locate(points: np.ndarray):
    """TO and generic tetrahedron containing each point.

    Parameters
    ----------
    points : (N, 3) index-space points

    Returns
    -------
    centre : (N, 3) TO centres
    tet : (N,) generic tetrahedron index in [0, 144)
    lam : (N, 4) barycentric coordinates in that tetrahedron
    """
    p = np.asarray(points, dtype=np.float64)
    centre = nearest_centre(p)
    d = p - centre
    ratio = np.concatenate([d @ (SQUARE_NEIGHBOURS.T / 2.0), d @ HEX_NEIGHBOURS.T / 1.5], axis=1)
    face = np.argmax(ratio, axis=1)
    frames, sectors, n_sectors = _face_sectors()
    centre_f = np.array([f["centre"] for f in faces()])[face]
    q = d - centre_f
    ang = np.arctan2(np.einsum("nc,nc->n", q, frames[face, 1]),
                     np.einsum("nc,nc->n", q, frames[face, 0])) % (2 * np.pi)
    n = n_sectors[face]
    sector = np.minimum((ang * n / (2 * np.pi)).astype(np.int64), n - 1)
    tet = sectors[face, sector]
    mats = barycentric_matrices()[tet]
    lam = np.einsum("nij,nj->ni", mats[:, :, :3], d) + mats[:, :, 3]
    return centre, tet, lam


def _key(points: np.ndarray) -> tuple:
    return tuple(np.round(np.asarray(points) * 4).astype(np.int64).ravel())


@cache
def neighbours():
    """Face neighbours of the generic tetrahedra.

    Face nu of a tetrahedron is the one opposite vertex v_nu (F_nu in §5.2). F_0 lies on the TO
    boundary, F_1..F_3 inside the TO.

    Returns
    -------
    tet : (144, 4) int, the neighbouring generic tetrahedron across each face
    shift : (144, 4, 3) float, lattice vector from this TO's centre to the neighbour's
        (zero inside the TO)
    """
    verts, _, _ = generic_tetrahedra()
    table = {}
    for s, shift in enumerate(np.concatenate([np.zeros((1, 3)), NEIGHBOUR_OFFSETS])):
        for t in range(144):
            for nu in range(4):
                face = np.delete(verts[t], nu, axis=0) + shift
                key = tuple(sorted(_key(face)[i:i + 3] for i in range(0, 9, 3)))
                table.setdefault(key, []).append((t, s, nu))
    nb = np.full((144, 4), -1, dtype=np.int64)
    shifts = np.zeros((144, 4, 3))
    all_shifts = np.concatenate([np.zeros((1, 3)), NEIGHBOUR_OFFSETS])
    for t in range(144):
        for nu in range(4):
            face = np.delete(verts[t], nu, axis=0)
            key = tuple(sorted(_key(face)[i:i + 3] for i in range(0, 9, 3)))
            others = [(t2, s) for t2, s, _ in table[key] if not (t2 == t and s == 0)]
            if len(others) != 1:
                raise RuntimeError(f"face {nu} of tetrahedron {t} has {len(others)} neighbours")
            nb[t, nu], shifts[t, nu] = others[0][0], all_shifts[others[0][1]]
    nb.flags.writeable = False
    shifts.flags.writeable = False
    return nb, shifts


def centres_covering(lo, hi) -> np.ndarray:
    """Centres of all TOs that meet the box [lo, hi] (index space).

    Parameters
    ----------
    lo, hi : (3,) box corners

    Returns
    -------
    (M, 3) centres
    """
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    out = []
    for first in (0.5, 1.5):
        axes = [
            np.arange(first + 2 * np.floor((a - 1 - first) / 2), b + 1 + EPS, 2.0)
            for a, b in zip(lo, hi, strict=True)
        ]
        c = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        out.append(c)
    c = np.concatenate(out)
    # a TO (|d_a| <= 1, sum |d_a| <= 3/2) meets the box iff the point of the box nearest to its
    # centre lies in it (both sets are convex and the TO is symmetric about its centre)
    near = np.clip(c, lo, hi) - c
    inside = (np.abs(near).max(axis=1) <= 1 + EPS) & (np.abs(near).sum(axis=1) <= 1.5 + EPS)
    return c[inside]


def contains(centre: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Whether each point lies in the (closed) TO around ``centre``: (N, 3), (N, 3) -> (N,)."""
    d = np.abs(np.asarray(points) - np.asarray(centre))
    return (d.max(axis=-1) <= 1 + EPS) & (d.sum(axis=-1) <= 1.5 + EPS)
