"""Bricks, visibility order, screen footprints and sort-last compositing (pure NumPy)."""

import itertools

import numpy as np
import pytest

from splineviz.core.bricks import BrickGrid, occluded, screen_footprint, value_margin
from splineviz.core.camera import Camera
from splineviz.core.compositing import Composite, Fragment, blend
from splineviz.core.raycast_reference import BACKGROUND, Frame


def test_bricks_cover_the_cells_once_and_read_their_halo():
    shape, halo = (23, 17, 9), 3
    g = BrickGrid(shape, size=(8, 5, 8), halo=halo)
    assert g.counts == (3, 4, 1)
    cells = np.zeros([n - 1 for n in shape], int)
    for b in g:
        (a0, b0), (a1, b1), (a2, b2) = b.inner
        cells[a0:b0, a1:b1, a2:b2] += 1
        for (lo, hi), (r0, r1), n in zip(b.inner, b.read, shape, strict=True):
            # the halo: ghost layers of real samples inside the data, none beyond it
            assert r0 == max(0, lo - halo) and r1 == min(n, hi + 1 + halo)
        assert b.touches_boundary(shape) == any(
            r0 == 0 or r1 == n for (r0, r1), n in zip(b.read, shape, strict=True))
    assert np.all(cells == 1)
    assert BrickGrid.split((257, 257, 129), 2, 1).counts == (2, 2, 2)


def test_read_boxes_keep_the_lattice_parity():
    """Truncated octahedra repeat every 2 grid steps: read boxes start at even offsets."""
    g = BrickGrid((40, 33, 21), size=7, halo=3, align=2)
    assert g.size == (8, 8, 8)
    for b in g:
        assert all(r0 % 2 == 0 for r0, _ in b.read)
        assert all(r0 <= max(0, lo - 3) for (r0, _), (lo, _) in zip(b.read, b.inner,
                                                                   strict=True))


@pytest.mark.parametrize("centred", [False, True])
def test_bricks_own_every_cell_once_within_their_samples(centred):
    """Unit cells between samples, or cubes centred at them (type-6: one more per axis):
    every cell of the ray caster's grid belongs to one brick, whose read box holds the
    samples the cell's stencil reads (the halo of the model) at its placement's offset."""
    shape, halo = (23, 17, 9), 1
    g = BrickGrid(shape, size=(8, 5, 8), halo=halo, centred=centred)
    grid = [n - 1 + centred for n in shape]
    owner = np.zeros(grid, int)
    for b in g:
        cells = g.cells(b)
        owner[tuple(slice(lo, hi) for lo, hi in cells)] += 1
        p = g.placement(b, (1.0, 2.0, 3.0))
        assert p.cells == cells and p.offset == tuple(r0 for r0, _ in b.read)
        assert p.shape == shape and p.centred == centred
        for (lo, hi), (r0, r1), n in zip(cells, b.read, shape, strict=True):
            # a cube reads its neighbours (ghosts beyond the data); a unit cell its corners
            need = (lo - 1, hi + 1) if centred else (lo, hi + 1)
            assert r0 <= max(need[0], 0) and min(need[1], n) <= r1
    assert np.all(owner == 1)


def test_placement_box_and_face_planes():
    g = BrickGrid((9, 9, 9), size=4, halo=1)
    spacing, origin = (1.0, 2.0, 0.5), (10.0, 0.0, -1.0)
    b = g[(0, 1, 0)]
    p = g.placement(b, origin)
    np.testing.assert_array_equal(p.box(), [[0, 4], [4, 8], [0, 4]])
    box = g.world_box(b, spacing, origin)
    np.testing.assert_allclose(box, np.asarray(origin)[:, None] + p.box()
                               * np.asarray(spacing)[:, None])
    planes = p.face_planes(spacing)
    # inner faces only: x high, y low, z high (y high and the low x, z faces are the data's)
    assert len(planes) == 3
    inside = box.mean(axis=1)
    for o, n in planes:
        assert np.dot(inside - np.asarray(o), n) > 0
        assert np.isclose(abs(np.dot(np.asarray(o), n)),
                          abs(np.dot(box[:, 0 if np.sum(n) > 0 else 1], n)))
    # centred cells: the box is shifted by half a cell and kept within the data box
    c = BrickGrid((9, 9, 9), size=4, halo=1, centred=True)
    np.testing.assert_array_equal(c.placement(c[(0, 1, 0)], origin).box(),
                                  [[0, 3.5], [3.5, 8], [0, 3.5]])


@pytest.mark.parametrize("centred", [False, True])
@pytest.mark.parametrize("eye", [(-30, 4, 50), (4.5, 4.5, 4.5), (3.8, 7.7, 8.2), (3, 20, -7),
                                 (100, 100, 100)])
def test_visibility_order_puts_occluders_first(eye, centred):
    """Brute force: a brick hit first by a ray from the eye comes before every brick the same
    ray meets later (centred cells: bricks meet half a cell before the cuts)."""
    g = BrickGrid((13, 13, 13), size=4, halo=0, centred=centred)
    spacing, origin = (1.0, 1.0, 1.0), (0.0, 0.0, 0.0)
    rank = {b.index: n for n, b in enumerate(g.visibility_order(eye, spacing, origin))}
    rng = np.random.default_rng(1)
    eye = np.asarray(eye, float)
    for target in rng.uniform(0, 12, size=(200, 3)):
        d = target - eye
        ts = np.linspace(0, 1.5, 600)
        pts = eye + ts[:, None] * d
        inside = np.all((pts >= 0) & (pts <= 12), axis=1)
        idx = np.clip((pts[inside] + 0.5 * centred) // 4, 0, 2).astype(int)
        seq = [tuple(i) for i, _ in itertools.groupby(map(tuple, idx))]
        for a, b in itertools.pairwise(seq):
            assert rank[a] < rank[b]


def test_screen_footprint_holds_the_projection_and_nearest_depth():
    cam = Camera((30, -40, 25), (5, 5, 5), view_up=(0, 0, 1), view_angle=35)
    box = np.array([[2.0, 6.0], [1.0, 4.0], [3.0, 9.0]])
    clip = cam.fit_clipping_range(box)
    (r0, r1, c0, c1), nearest, hull = screen_footprint(cam, box, (200, 150), clip)
    pts = np.random.default_rng(0).uniform(box[:, 0], box[:, 1], size=(500, 3))
    _, dirs = cam.rays((200, 150))
    for p in pts:
        v = (p - np.asarray(cam.position))
        v /= np.linalg.norm(v)
        r, c = np.unravel_index(np.argmax(dirs.reshape(-1, 3) @ v), (150, 200))
        assert r0 <= r < r1 and c0 <= c < c1
        # the pixel is inside the hull: a hit everywhere else does not hide the box
        depth = np.zeros((150, 200), np.float32)
        hit = np.ones((150, 200), bool)
        hit[r, c] = False
        assert not occluded(depth, hit, (r0, r1, c0, c1), nearest, hull)
    assert np.all(cam.window_depth(pts, clip) >= nearest)
    # a box reaching behind the eye covers the whole image from depth 0
    assert screen_footprint(cam, np.array([[20, 40], [-50, -30], [0, 30]]), (200, 150),
                            clip) == ((0, 150, 0, 200), 0.0, None)


def test_occlusion_needs_every_pixel_nearer():
    depth = np.full((10, 10), 0.5, np.float32)
    hit = np.ones((10, 10), bool)
    assert occluded(depth, hit, (2, 5, 2, 5), 0.6)
    assert not occluded(depth, hit, (2, 5, 2, 5), 0.5)  # equal depth may be the same surface
    hit[3, 3] = False
    assert not occluded(depth, hit, (2, 5, 2, 5), 0.6)
    assert occluded(depth, hit, (4, 4, 0, 10), 0.0)  # outside the image
    # only pixels inside the projected box count: a counter-clockwise (column, row) square
    # around pixel (4, 4) leaves the missing pixel (3, 3) out
    square = np.array([[3.5, 3.5], [4.5, 3.5], [4.5, 4.5], [3.5, 4.5]])
    assert occluded(depth, hit, (2, 5, 2, 5), 0.6, square)
    hit[4, 4] = False
    assert not occluded(depth, hit, (2, 5, 2, 5), 0.6, square)


def test_value_margin_widens_by_ghosts_and_negative_weights():
    assert value_margin(2.0, 5.0, 0, 0.0, True) == (2.0, 5.0)
    lo, hi = value_margin(2.0, 5.0, 1, 0.25, False)
    assert (lo, hi) == (2.0 - 0.75, 5.0 + 0.75)
    lo_b, hi_b = value_margin(2.0, 5.0, 1, 0.25, True)
    assert lo_b < lo and hi_b > hi


def _random_frames(rng, n, shape=(12, 16)):
    frames = []
    for _ in range(n):
        hit = rng.random(shape) < 0.4
        depth = np.where(hit, rng.random(shape), 1.0).astype(np.float32)
        pos = np.where(hit[..., None], rng.random(shape + (3,)), np.nan)
        color = rng.integers(0, 256, shape + (4,), dtype=np.uint8)
        frames.append(Frame(hit, pos, pos.copy(), depth, color))
    return frames


def test_nearest_composite_is_the_per_pixel_minimum_in_any_order():
    rng = np.random.default_rng(3)
    frames = _random_frames(rng, 5)
    frags = [Fragment.from_frame((i, 0, 0), f) for i, f in enumerate(frames)]
    depth = np.stack([f.depth for f in frames])
    best = np.argmin(depth, axis=0)
    for order in (range(5), reversed(range(5))):
        comp = Composite((16, 12))
        for i in order:
            comp.add_nearest(frags[i])
        out = comp.frame()
        np.testing.assert_array_equal(out.hit, np.any([f.hit for f in frames], axis=0))
        np.testing.assert_array_equal(out.depth, depth.min(axis=0))
        pick = np.take_along_axis(np.stack([f.color for f in frames]),
                                  best[None, ..., None], 0)[0]
        np.testing.assert_array_equal(out.color[out.hit], pick[out.hit])
        bg = np.rint(255 * np.asarray(BACKGROUND)).astype(np.uint8)
        np.testing.assert_array_equal(out.color[~out.hit][:, :3],
                                      np.broadcast_to(bg, (int((~out.hit).sum()), 3)))


def test_painting_back_to_front_gives_the_nearest_when_order_matches_depth():
    rng = np.random.default_rng(4)
    frames = _random_frames(rng, 4)
    # brick k's hits lie in the depth band [k/4, (k+1)/4): a front-to-back order of bricks
    for k, f in enumerate(frames):
        f.depth[f.hit] = (k + f.depth[f.hit]) / 4
    frags = [Fragment.from_frame((k, 0, 0), f) for k, f in enumerate(frames)]
    near, paint = Composite((16, 12)), Composite((16, 12))
    for fr in frags:
        near.add_nearest(fr)
    for fr in reversed(frags):
        paint.paint(fr)
    a, b = near.frame(), paint.frame()
    np.testing.assert_array_equal(a.depth, b.depth)
    np.testing.assert_array_equal(a.color, b.color)
    assert blend(a, 0.4).shape == (12, 16, 3)


def test_fragment_crops_to_its_hits():
    f = _random_frames(np.random.default_rng(5), 1)[0]
    f.hit[:] = False
    f.hit[3:5, 7:12] = True
    frag = Fragment.from_frame((0, 0, 0), f)
    assert frag.rect == (3, 5, 7, 12) and frag.hit.all()
    # a window of a bigger frame: the rectangle in the whole frame's pixels
    moved = Fragment.from_frame((0, 0, 0), f, offset=(20, 30))
    assert moved.rect == (23, 25, 37, 42)
    np.testing.assert_array_equal(moved.depth, frag.depth)
    f.hit[:] = False
    assert Fragment.from_frame((0, 0, 0), f, offset=(20, 30)).rect == (0, 0, 0, 0)
