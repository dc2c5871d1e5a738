"""The type-6 tetrahedral partition Delta_6 (thesis §4.4, Fig. 4.2 right).

Everything is in *index space* (grid spacing h = 1): data points are the integer points and the
cube Q_ijk is centred at data point (i, j, k) with vertices (i +- 1/2, j +- 1/2, k +- 1/2).
Connecting the cube centre with the 8 cube vertices gives 6 pyramids; each pyramid is split by
its two diagonal planes into 4 tetrahedra, 24 congruent *generic tetrahedra* per cube. Each
tetrahedron is [v0, v1, v2, v3] with v0 the cube centre, v1 the centroid of one cube face and
v2, v3 the two vertices of one edge of that face.

Generation (no hand-typed tables): the reference tetrahedron

    v0 = (0, 0, 0), v1 = (1/2, 0, 0), v2 = (1/2, -1/2, 1/2), v3 = (1/2, 1/2, 1/2)

has the local frame n_F = 2 (v1 - v0) = e_x, n_R = v3 - v2 = e_y, n_T = v2 + v3 - 2 v1 = e_z.
Tetrahedron ``t`` is the image of the reference under the proper rotation ``FRAMES[t]`` of the
cube whose first column is the outer face normal n_F and whose last column is the normal n_T of
the edge's other face; every other rule (masks, domain points) is transported with the same
rotation. The 24 rotations of the cube give the 24 tetrahedra exactly once.

Point location: for a point p relative to the cube centre, the pyramid is given by the axis of
the largest |p_a| (and its sign), the tetrahedron inside it by the largest of the two remaining
|p_b| (and its sign) -- both choices are the half-spaces of the six slicing planes.

Conventions: ``vertices`` arrays are (24, 4, 3) relative to the cube centre; barycentric
matrices are (24, 4, 4) with ``lam = M @ (p, 1)`` for p relative to the cube centre (so the
same matrix serves every cube); ``FACE_NEIGHBOURS[t, m]`` is the (tetrahedron, cube offset)
across the face opposite vertex m.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from splineviz.core import bform

#: number of generic tetrahedra per cube
N_TETS = 24

#: tolerance for geometric coincidence tests in index units
EPS = 1e-9

#: the reference tetrahedron [v0, v1, v2, v3] (thesis §4.4) in the cube around the origin
REFERENCE_TET = np.array(
    [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.5, -0.5, 0.5], [0.5, 0.5, 0.5]]
)
REFERENCE_TET.flags.writeable = False


def _frame(axis_f: int, sign_f: int, axis_t: int, sign_t: int) -> np.ndarray:
    """Proper rotation, columns (n_F, n_R, n_T): n_F = sign_f e_axis_f, n_T = sign_t e_axis_t."""
    n_f = sign_f * np.eye(3)[axis_f]
    n_t = sign_t * np.eye(3)[axis_t]
    # right-handed reference frame: e_y = e_z x e_x, so n_R = n_T x n_F keeps det = +1
    n_r = np.cross(n_t, n_f)
    return np.stack([n_f, n_r, n_t], axis=1)


@cache
def _tables():
    frames = []
    lookup = -np.ones((3, 2, 3, 2), dtype=np.int64)
    for a in range(3):
        for sa_i, sa in enumerate((1, -1)):
            # edge faces in the order (a + 2, a + 1) so that tetrahedron 0 is the reference
            for b in ((a + 2) % 3, (a + 1) % 3):
                for sb_i, sb in enumerate((1, -1)):
                    lookup[a, sa_i, b, sb_i] = len(frames)
                    frames.append(_frame(a, sa, b, sb))
    frames = np.array(frames)  # (24, 3, 3)
    vertices = np.einsum("tij,mj->tmi", frames, REFERENCE_TET)  # (24, 4, 3)
    for arr in (frames, vertices, lookup):
        arr.flags.writeable = False
    return frames, vertices, lookup


#: (24, 3, 3) rotations: columns n_F, n_R, n_T of each generic tetrahedron
FRAMES: np.ndarray = _tables()[0]
#: (24, 4, 3) vertices [v0, v1, v2, v3] of the generic tetrahedra relative to the cube centre
VERTICES: np.ndarray = _tables()[1]
#: (3, 2, 3, 2) tetrahedron id from (pyramid axis, sign index, edge-face axis, sign index);
#: sign index 0 is +, 1 is -; -1 where the two axes coincide
TET_LOOKUP: np.ndarray = _tables()[2]


@cache
def barycentric_matrices() -> np.ndarray:
    """(24, 4, 4) M_T^{-1} of the generic tetrahedra, for points relative to the cube centre."""
    out = bform.barycentric_matrix(VERTICES)
    out.flags.writeable = False
    return out


def barycentric_gradients() -> np.ndarray:
    """(24, 4, 3) d(phi_m)/dx of the barycentric coordinates (index space, constant per tet)."""
    return barycentric_matrices()[:, :, :3]


def tet_volumes() -> np.ndarray:
    """(24,) volumes of the generic tetrahedra (each 1/24 of the unit cube)."""
    e = VERTICES[:, 1:] - VERTICES[:, :1]
    return np.abs(np.linalg.det(e)) / 6.0


def locate(upoints: np.ndarray):
    """Cube and generic tetrahedron containing each index-space point.

    Points on a shared face go to one of the touching tetrahedra (consistently, by the
    order of the comparisons); a continuous spline has the same value there on both sides.

    Parameters
    ----------
    upoints : (N, 3) float64 index-space points

    Returns
    -------
    cube : (N, 3) int64 data-point index (i, j, k) of the cube centre
    tet : (N,) int64 generic tetrahedron id in [0, 24)
    local : (N, 3) float64 point relative to the cube centre, in [-1/2, 1/2]^3
    """
    u = np.asarray(upoints, dtype=np.float64)
    cube = np.floor(u + 0.5).astype(np.int64)
    local = u - cube
    mag = np.abs(local)
    a = np.argmax(mag, axis=1)
    rows = np.arange(len(u))
    # the two remaining axes of each point, in cyclic order after a
    b1 = (a + 1) % 3
    b2 = (a + 2) % 3
    b = np.where(mag[rows, b1] >= mag[rows, b2], b1, b2)
    sa = (local[rows, a] < 0).astype(np.int64)
    sb = (local[rows, b] < 0).astype(np.int64)
    tet = TET_LOOKUP[a, sa, b, sb]
    return cube, tet, local


@cache
def face_neighbours():
    """Face-neighbour table of the generic tetrahedra, inside a cube and across cube faces.

    Returns
    -------
    tet : (24, 4) int64
        ``tet[t, m]``: the generic tetrahedron sharing the face of ``t`` opposite vertex m.
    offset : (24, 4, 3) int64
        Cube offset of that neighbour (zero inside the cube; n_F across the cube face m = 0).
    opposite : (24, 4) int64
        The vertex of the neighbour that is not on the shared face.
    """
    offsets = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)])
    nb_tet = -np.ones((N_TETS, 4), dtype=np.int64)
    nb_off = np.zeros((N_TETS, 4, 3), dtype=np.int64)
    nb_opp = -np.ones((N_TETS, 4), dtype=np.int64)
    for t in range(N_TETS):
        for m in range(4):
            face = np.delete(VERTICES[t], m, axis=0)  # (3, 3)
            for off in offsets:
                cand = VERTICES + off  # (24, 4, 3)
                # vertex of candidate s equal to face vertex f
                eq = np.all(np.abs(cand[:, :, None, :] - face[None, None]) < EPS, axis=-1)
                shared = eq.any(axis=2).sum(axis=1)  # (24,) vertices of s on the face
                for s in np.flatnonzero(shared == 3):
                    if s == t and not off.any():
                        continue
                    nb_tet[t, m], nb_off[t, m] = s, off
                    nb_opp[t, m] = int(np.flatnonzero(~eq[s].any(axis=1))[0])
    if (nb_tet < 0).any():
        raise AssertionError("type-6 neighbour table incomplete")  # a bug, not user input
    for arr in (nb_tet, nb_off, nb_opp):
        arr.flags.writeable = False
    return nb_tet, nb_off, nb_opp


def world_vertices(cube: np.ndarray, tet: np.ndarray) -> np.ndarray:
    """(N, 4, 3) index-space vertices of tetrahedra ``tet`` in cubes ``cube`` ((N, 3) ints)."""
    return VERTICES[np.asarray(tet)] + np.asarray(cube, dtype=np.float64)[:, None, :]
