"""The type-6 partition (thesis §4.4): generic tetrahedra, tiling, neighbours, point location."""

from itertools import product

import numpy as np
import pytest

from splineviz.core import bform
from splineviz.core.partitions import type6

RNG = np.random.default_rng(6)


def _bary_all(local):
    """(N, 24, 4) barycentric coordinates of local points in all 24 generic tetrahedra."""
    m = type6.barycentric_matrices()
    return np.einsum("tij,nj->nti", m[:, :, :3], local) + m[None, :, :, 3]


def test_vertex_roles_of_every_generic_tet():
    """v0 cube centre, v1 a face centroid, v2/v3 cube vertices on an edge of that face."""
    v = type6.VERTICES
    assert v.shape == (24, 4, 3)
    assert np.all(v[:, 0] == 0)
    v1 = v[:, 1]
    assert np.all(np.sort(np.abs(v1), axis=1) == [0, 0, 0.5])
    assert np.all(np.abs(v[:, 2:]) == 0.5)
    diff = np.abs(v[:, 3] - v[:, 2])
    assert np.all(np.sort(diff, axis=1) == [0, 0, 1])  # one cube edge
    axis = np.argmax(np.abs(v1), axis=1)
    rows = np.arange(24)
    for m in (2, 3):
        assert np.all(v[rows, m, axis] == v1[rows, axis])  # on the face of v1
    assert np.allclose(v[0], type6.REFERENCE_TET)
    # 24 distinct tetrahedra (as vertex sets)
    keys = {tuple(sorted(map(tuple, t))) for t in v.tolist()}
    assert len(keys) == 24


def test_frames_are_the_24_cube_rotations_and_map_the_reference():
    f = type6.FRAMES
    assert np.allclose(np.linalg.det(f), 1.0)
    assert np.allclose(np.einsum("tji,tjk->tik", f, f), np.eye(3))
    assert len({tuple(np.rint(r).astype(int).ravel()) for r in f}) == 24
    v = type6.VERTICES
    n_f = 2 * (v[:, 1] - v[:, 0])
    n_r = v[:, 3] - v[:, 2]
    n_t = v[:, 2] + v[:, 3] - 2 * v[:, 1]
    assert np.allclose(np.stack([n_f, n_r, n_t], axis=2), f)


def test_volumes_add_up_to_the_cube():
    vol = type6.tet_volumes()
    assert np.allclose(vol, 1 / 24)
    assert vol.sum() == pytest.approx(1.0, abs=1e-14)
    # rotations of the reference keep its orientation
    e = type6.VERTICES[:, 1:] - type6.VERTICES[:, :1]
    assert np.allclose(np.linalg.det(e), np.linalg.det(e[0]))


def test_barycentric_matrices_and_gradients():
    m = type6.barycentric_matrices()
    homog = np.concatenate([type6.VERTICES, np.ones((24, 4, 1))], axis=2)
    assert np.allclose(np.einsum("tij,tkj->tik", m, homog), np.eye(4))
    g = type6.barycentric_gradients()
    assert np.allclose(g.sum(axis=1), 0.0)  # the coordinates sum to 1 everywhere
    assert np.allclose(m, bform.barycentric_matrix(type6.VERTICES))


def test_random_points_fall_in_exactly_one_tet_and_locate_finds_it():
    u = RNG.uniform(-4, 9, size=(20000, 3))
    cube, tet, local = type6.locate(u)
    assert np.allclose(cube + local, u)
    assert np.all(np.abs(local) <= 0.5)
    lam = _bary_all(local)
    inside = np.all(lam > -1e-12, axis=2)
    assert np.all(inside.sum(axis=1) == 1)
    assert np.array_equal(np.argmax(inside, axis=1), tet)


def test_points_on_faces_edges_and_vertices_are_located_validly():
    # points exactly on the slicing planes, cube faces and corners (ties in locate)
    grid = np.array(list(product([-0.5, -0.25, 0.0, 0.25, 0.5], repeat=3)))
    u = np.concatenate([grid, grid + [3, 1, 2]])
    cube, tet, local = type6.locate(u)
    m = type6.barycentric_matrices()[tet]
    lam = np.einsum("nij,nj->ni", m[:, :, :3], local) + m[:, :, 3]
    assert lam.min() > -1e-12


def test_neighbour_tables_are_symmetric_and_complete():
    nb, off, opp = type6.face_neighbours()
    v = type6.VERTICES
    inside = across = 0
    for t in range(24):
        for m in range(4):
            s, o, w = nb[t, m], off[t, m], opp[t, m]
            # symmetric: the neighbour's neighbour across the same face is t
            back = [k for k in range(4) if nb[s, k] == t and np.array_equal(off[s, k], -o)]
            assert len(back) == 1
            assert opp[s, back[0]] == m
            # shared face: same three points
            face_t = {tuple(p) for p in np.delete(v[t], m, axis=0)}
            face_s = {tuple(p) for p in np.delete(v[s], w, axis=0) + o}
            assert face_t == face_s
            if o.any():
                across += 1
                assert m == 0 and w == 0
                assert np.array_equal(o, np.rint(type6.FRAMES[t][:, 0]).astype(int))
            else:
                inside += 1
    assert inside == 72 and across == 24  # 36 interior faces, 24 cube-face triangles


def test_world_vertices_translate_generic_tets():
    cube = np.array([[2, 3, 4], [0, 0, 0]])
    tv = type6.world_vertices(cube, np.array([5, 0]))
    assert np.allclose(tv[0], type6.VERTICES[5] + [2, 3, 4])
    assert np.allclose(tv[1], type6.REFERENCE_TET)
