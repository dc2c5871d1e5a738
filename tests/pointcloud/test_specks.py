"""``drop_specks``: the few-triangle pieces the front seeds on scanner outliers are dropped,
a mesh made only of small pieces is kept."""

import numpy as np

from splineviz.pointcloud.remesh import MIN_PIECE_FACES, drop_specks


def _strip(n, offset):
    """A strip of ``n`` triangles (n + 2 vertices) shifted by ``offset``."""
    x = np.arange(n + 2) // 2
    y = np.arange(n + 2) % 2
    v = np.column_stack([x, y, np.zeros(n + 2)]).astype(float) + offset
    f = np.array([[i, i + 1, i + 2] for i in range(n)])
    return v, f


def test_small_pieces_beside_a_large_one_are_dropped():
    big_v, big_f = _strip(MIN_PIECE_FACES + 10, [0.0, 0.0, 0.0])
    speck_v, speck_f = _strip(3, [0.0, 0.0, 5.0])
    v = np.vstack([speck_v, big_v])  # the speck first: the kept vertices are renumbered
    f = np.vstack([speck_f, big_f + len(speck_v)])
    out_v, out_f = drop_specks(v, f)
    np.testing.assert_array_equal(out_v, big_v)
    np.testing.assert_array_equal(out_f, big_f)


def test_a_mesh_of_small_pieces_only_is_kept():
    v, f = _strip(3, [0.0, 0.0, 0.0])
    w, g = _strip(2, [0.0, 0.0, 3.0])
    both_v, both_f = np.vstack([v, w]), np.vstack([f, g + len(v)])
    out_v, out_f = drop_specks(both_v, both_f)
    assert out_v is both_v and out_f is both_f
