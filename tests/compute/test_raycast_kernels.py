"""The OpenCL ray casters against the NumPy reference (issue 4 acceptance criteria).

Models with kernels: trilinear (exact cubic per cell), the type-6 splines cubic-c1 and
super-quadratic, and the truncated-octahedral Q_2 (B-coefficients from the stencils, blossoms
along the ray).

Marschner-Lobb 41^3, tooth.nrrd and bonsai.vti from three cameras each at 160x120, and a
clipped view (about a minute on two cores). The references use the core
``"trilinear"`` model, so this also checks that the kernel computes the same spline.

The real data are uint8: at an integer isovalue whole cell edges and faces can lie exactly on
the surface, where "first root" is decided by float rounding (float32 on the device, float64
in NumPy). The accuracy checks therefore use half-integer isovalues.
"""

import numpy as np
import pytest

from splineviz.compute.raycast import RayCaster, RayCastError, numpy_cell_bounds
from splineviz.core.camera import Camera
from splineviz.core.raycast_reference import reference_raycast
from splineviz.core.splines import build_spline
from splineviz.core.volume import Volume

from .helpers import HAVE_CL, cameras, compare_frames, load_volume, marschner_lobb

needs_cl = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
SIZE = (160, 120)


def _check(metrics):
    assert metrics["hit_agreement"] >= 0.995, metrics
    assert metrics["pos_ok"] >= 0.995 and metrics["normal_ok"] >= 0.995, metrics
    assert metrics["value_max"] <= 1e-5, metrics
    assert metrics["clip_violations"] == 0, metrics
    assert metrics["both"] > 500, metrics  # the view must actually show the surface


KERNEL_MODELS = ["trilinear", "cubic-c1", "super-quadratic", "to-quadratic"]


def _run(vol, iso, cam, planes=(), step=0.25, model="trilinear"):
    rc = RayCaster(vol, model=model)
    rc.set_isovalue(iso)
    assert rc.stats["path"] == "opencl"
    frame = rc.render(cam, SIZE, clip_planes=planes)
    spline = build_spline(vol, model)
    ref = reference_raycast(spline, cam, SIZE, iso, clip_planes=planes, step=step)
    return frame, ref, compare_frames(frame, ref, spline, iso, planes)


@needs_cl
@pytest.mark.parametrize("model", KERNEL_MODELS)
@pytest.mark.parametrize("cam_index", [0, 1, 2])
def test_marschner_lobb_matches_reference(cam_index, model):
    vol, iso = marschner_lobb(41)
    frame, ref, m = _run(vol, iso, cameras(vol)[cam_index], model=model)
    _check(m)
    hit = frame.hit & ref.hit
    # depth follows position: the same few ill-conditioned (grazing) pixels may differ more
    ddepth = np.abs(frame.depth[hit] - ref.depth[hit])
    assert np.mean(ddepth <= 1e-5) >= 0.995
    assert np.all(frame.depth[~frame.hit] == 1)
    # Phong in the kernel and in NumPy: the same formula, up to float32 rounding
    diff = np.abs(frame.color[hit].astype(int) - ref.color[hit].astype(int)).max(axis=1)
    assert np.mean(diff <= 1) >= 0.995
    np.testing.assert_array_equal(frame.color[~frame.hit & ~ref.hit],
                                  ref.color[~frame.hit & ~ref.hit])


@needs_cl
@pytest.mark.parametrize("model", KERNEL_MODELS)
def test_tooth_matches_reference(model):
    vol = load_volume("tooth.nrrd")
    _, _, m = _run(vol, 100.5, cameras(vol)[0], step=0.5, model=model)
    _check(m)


@needs_cl
@pytest.mark.parametrize("model", KERNEL_MODELS)
def test_tooth_clipped_is_exact_cut(model):
    vol = load_volume("tooth.nrrd")
    c = np.asarray(vol.bounds).mean(axis=1)
    planes = [(c, (0.3, -1.0, 0.2)), (c + (0, 0, 30), (0, 0, -1.0))]
    frame, ref, m = _run(vol, 100.5, cameras(vol)[0], planes, step=0.5, model=model)
    _check(m)
    # the cut shows the inside: some hits lie on the back side of the surface
    unclipped = RayCaster(vol, model=model)
    unclipped.set_isovalue(100.5)
    full = unclipped.render(cameras(vol)[0], SIZE)
    assert np.sum(frame.hit & full.hit & (frame.depth > full.depth + 1e-4)) > 100


@needs_cl
@pytest.mark.parametrize("name,iso,cam_index", [("tooth.nrrd", 100.5, 1), ("tooth.nrrd", 100.5, 2),
                                                ("bonsai.vti", 40.5, 0), ("bonsai.vti", 40.5, 1),
                                                ("bonsai.vti", 40.5, 2)])
def test_real_data_matches_reference_more_views(name, iso, cam_index):
    vol = load_volume(name)
    _, _, m = _run(vol, iso, cameras(vol)[cam_index], step=0.5)
    _check(m)


@needs_cl
@pytest.mark.slow
@pytest.mark.parametrize("model", ["cubic-c1", "super-quadratic", "to-quadratic"])
@pytest.mark.parametrize("name,iso,cam_index", [("tooth.nrrd", 100.5, 1), ("tooth.nrrd", 100.5, 2),
                                                ("bonsai.vti", 40.5, 0), ("bonsai.vti", 40.5, 1),
                                                ("bonsai.vti", 40.5, 2)])
def test_tet_models_real_data_more_views_slow(name, iso, cam_index, model):
    vol = load_volume(name)
    _, _, m = _run(vol, iso, cameras(vol)[cam_index], step=0.5, model=model)
    _check(m)


@needs_cl
@pytest.mark.parametrize("model", ["cubic-c1", "super-quadratic"])
def test_type6_tet_codes_match_core_coefficients(model):
    # every tet whose core B-coefficients straddle the isovalue has its bit set, no other
    vol, iso = marschner_lobb(13)
    rc = RayCaster(vol, model=model)
    rc.set_isovalue(iso)
    cls = rc.classify_all()
    codes = np.zeros(int(np.prod(rc._cells)), np.uint32)
    codes[cls.cells] = cls.codes
    # classify_all fills the brick cache that the frames read, at the current epoch: per
    # level-1 brick a slot (epoch << 24 | pool entry), per cube of it VALID | tet code
    q = rc._device.queue
    slots, pool = rc._slots.get(queue=q), rc._pool.get(queue=q)
    i, j, k = np.unravel_index(cls.cells, rc._cells)
    _, _, by, bz = rc._levels[0]
    slot = slots[((i >> 1) * by + (j >> 1)) * bz + (k >> 1)]
    np.testing.assert_array_equal(slot >> 24, rc._epoch)
    entry = pool[(slot & 0xFFFFFF) * 8 + (((i & 1) << 2) | ((j & 1) << 1) | (k & 1))]
    np.testing.assert_array_equal(entry, cls.codes | np.uint32(0x80000000))
    spline = rc.spline
    cubes = spline.all_cubes()
    bits = np.zeros((len(cubes), 24), dtype=bool)
    for t in range(24):
        c = spline.tet_coefficients(cubes, np.full(len(cubes), t))
        bits[:, t] = (c.min(axis=1) <= iso) & (iso <= c.max(axis=1))
    got = ((codes[:, None] >> np.arange(24)) & 1).astype(bool)
    # float32 on the device: only coefficients within rounding of iso may differ
    assert np.mean(got == bits) > 0.9999
    assert rc.stats["active_tets"] == got.sum() and rc.stats["active_cells"] == (codes != 0).sum()


def _random_volume(shape=(13, 9, 11), seed=3):
    rng = np.random.default_rng(seed)
    # smooth-ish field so that some macro cubes are empty and some are not
    x, y, z = np.meshgrid(*(np.linspace(-1, 1, n) for n in shape), indexing="ij")
    return Volume(x**2 + 0.5 * y**2 + z**2 + 0.05 * rng.standard_normal(shape))


@needs_cl
def test_classification_compaction_and_skip_volume():
    vol = _random_volume()
    rc = RayCaster(vol, model="trilinear")
    rc.set_isovalue(0.6)
    vmin, vmax = numpy_cell_bounds(vol.data)
    active = (vmin <= np.float32(0.6)) & (np.float32(0.6) <= vmax)
    np.testing.assert_array_equal(rc.active_cells(), np.flatnonzero(active.ravel()))
    assert rc.stats["active_cells"] == active.sum() > 0
    # skip codes: 255 where the level-1 node (2^3 cells) may hold the surface, else the
    # largest empty macro cube, from a NumPy min-max octree of the cell bounds
    iso = np.float32(0.6)
    lo, hi = vmin, vmax
    expected = np.full(active.shape, -1)
    empty_so_far = np.ones(active.shape, bool)
    idx = np.indices(active.shape)
    for level in range(1, int(np.ceil(np.log2(max(active.shape)))) + 1):
        pad = [(0, n % 2) for n in lo.shape]
        lo = np.pad(lo, pad, constant_values=np.inf)
        hi = np.pad(hi, pad, constant_values=-np.inf)
        shape = [n // 2 for n in lo.shape]
        lo = lo.reshape(shape[0], 2, shape[1], 2, shape[2], 2).min(axis=(1, 3, 5))
        hi = hi.reshape(shape[0], 2, shape[1], 2, shape[2], 2).max(axis=(1, 3, 5))
        node = tuple(i >> level for i in idx)
        empty_so_far &= ~((lo <= iso) & (iso <= hi))[node]
        expected[empty_so_far] = level
    skip = rc.skip_volume()
    np.testing.assert_array_equal(skip, np.where(expected < 0, 255, expected))
    assert (skip == 255).any() and (skip != 255).any() and (skip > 1).any()
    assert not active[skip != 255].any()  # leaping never skips a candidate cell
    # a new isovalue reclassifies; a new volume rebuilds the octree
    rc.set_isovalue(10.0)
    assert len(rc.active_cells()) == 0 and rc.stats["active_cells"] == 0
    assert (rc.skip_volume() != 255).all()
    rc.set_volume(Volume(vol.data * 10))
    rc.classify_all()
    assert rc.stats["active_cells"] == np.sum((vmin * 10 <= 10) & (10 <= vmax * 10))


@needs_cl
def test_empty_space_leaping_changes_nothing():
    # the same frame with every cell forced active (no leaping) and with the skip volume
    vol, iso = marschner_lobb(25)
    rc = RayCaster(vol, model="trilinear")
    rc.set_isovalue(iso)
    cam = cameras(vol)[1]
    leaped = rc.render(cam, (80, 60))
    assert (rc.skip_volume() != 255).any()
    # octree bounds that hold every isovalue: every cell a candidate, nothing leaped
    q = rc._device.queue
    b = rc._bounds.get(queue=q)
    b[0::2], b[1::2] = -np.inf, np.inf
    rc._bounds.set(b, queue=q)
    assert (rc.skip_volume() == 255).all()
    dense = rc.render(cam, (80, 60))
    np.testing.assert_array_equal(leaped.hit, dense.hit)
    np.testing.assert_allclose(leaped.position[leaped.hit], dense.position[dense.hit], atol=1e-4)


def test_numpy_path_and_errors(monkeypatch):
    vol = _random_volume((6, 6, 6))
    rc = RayCaster(vol, model="trilinear", device="numpy")
    assert rc.stats["path"] == "numpy" and rc.stats["device"] == "numpy"
    with pytest.raises(RayCastError, match="isovalue"):
        rc.render(Camera((3, -10, 3), (2.5, 2.5, 2.5)), (8, 6))
    rc.set_isovalue(0.6)
    vmin, vmax = numpy_cell_bounds(vol.data)
    assert rc.stats["active_cells"] == np.sum((vmin <= 0.6) & (0.6 <= vmax))
    with pytest.raises(RayCastError, match="unknown spline model"):
        RayCaster(vol, model="quartic")
    with pytest.raises(RayCastError, match="at least 2 samples"):
        RayCaster(np.zeros((1, 4, 4)), model="trilinear", device="numpy")
    with pytest.raises(RayCastError, match="finite"):
        rc.set_isovalue(np.nan)


@needs_cl
def test_to_relevance_bits_match_core_coefficients():
    # every (TO, tet) piece of a cell whose core B-coefficients straddle the isovalue is marked
    from splineviz.compute.to_tables import cell_classes
    from splineviz.core.splines import to_quadratic

    vol, iso = marschner_lobb(9)
    rc = RayCaster(vol, model="to-quadratic")
    rc.set_isovalue(iso)
    result = rc.classify_all()
    slot = dict(zip(result.cells.tolist(), range(len(result.cells)), strict=True))
    start, centre, tet = cell_classes()
    spline = rc.spline
    cells = np.argwhere(np.ones(rc._cells, bool))
    agree = total = 0
    for flat, (i, j, k) in enumerate(cells):
        cls = 4 * (i % 2) + 2 * (j % 2) + (k % 2)
        ents = np.arange(start[cls], start[cls + 1])
        base = np.rint(centre[ents] + (i, j, k) - 0.5).astype(np.int64) + 3
        c = to_quadratic.coefficients(spline._padded, base, tet[ents], spline.k)
        want = (c.min(axis=1) <= iso) & (iso <= c.max(axis=1))
        if flat in slot:
            words = result.codes[slot[flat]]
            got = np.array([(words[e >> 5] >> (e & 31)) & 1 for e in range(len(ents))], bool)
        else:
            got = np.zeros(len(ents), bool)
        agree += np.sum(got == want)
        total += len(ents)
    assert total > 1000 and agree / total > 0.9999


@pytest.mark.parametrize("k", [2, 1.5])
def test_to_class_points_walsh_rows_equal_data_rows(k):
    # the generated relevance test sums each point from the Walsh sums of its TOs: the same
    # linear functional of the data as its data row, for every point of every class
    from splineviz.compute.to_tables import class_points, walsh_sums
    from splineviz.core.partitions import truncated_octahedra as to

    signs = np.sign(to.DATA_OFFSETS)  # (8, 3), the x, y, z signs of a TO's data points
    chi = np.array([[np.prod(signs[i][[a for a, bit in enumerate((4, 2, 1)) if m & bit]])
                     for i in range(8)] for m in range(8)])
    v = np.random.default_rng(3).normal(size=(4, 8))
    assert np.allclose(walsh_sums(v), v @ chi.T)
    t = class_points(k, 5)
    rng = np.random.default_rng(4)
    for c in range(8):
        vals = rng.normal(size=t["union_start"][c + 1] - t["union_start"][c])
        walsh = walsh_sums(vals[t["to_union"][t["to_start"][c]:t["to_start"][c + 1]]]).ravel()
        for p in range(t["pt_start"][c], t["pt_start"][c + 1]):
            d = slice(t["rows"][p], t["rows"][p + 1])
            w = slice(t["wrows"][p], t["wrows"][p + 1])
            want = t["weights"][d] @ vals[t["cols"][d]]
            assert abs(t["wweights"][w] @ walsh[t["wcols"][w]] - want) < 1e-12, (c, p)
    # and shorter: 6.6 terms a point instead of 14.0 (k = 2), 8.2 instead of 15.1 (k = 1.5)
    assert np.diff(t["wrows"]).mean() < 0.6 * np.diff(t["rows"]).mean()


def _subcells_crossed(p0, d, n):
    """The subcells of an n^3 split of the unit cell that the segment p0 + s d, s in [0, 1],
    crosses with positive length (exact: the midpoints between its plane crossings)."""
    s = [0.0, 1.0]
    for a in range(3):
        if d[a] != 0:
            s.extend(t for t in (np.arange(1, n) / n - p0[a]) / d[a] if 0 < t < 1)
    s = np.sort(s)
    mid = p0 + 0.5 * (s[1:] + s[:-1])[:, None] * d
    return {tuple(c) for c in np.clip(np.floor(mid * n).astype(int), 0, n - 1)}


def test_to_subcell_masks_hold_every_piece_a_segment_meets():
    # the rays test only the pieces of the subcells their segment crosses: a piece met by a
    # chord of the cell must be in the union of those masks (and most pieces are not)
    from splineviz.compute.to_tables import SUBCELLS, cell_classes, subcell_masks
    from splineviz.core.partitions import truncated_octahedra as to

    start, centre, tet = cell_classes()
    bary = to.barycentric_matrices()  # (144, 4, 4): rows (a, b, c, w), lambda = a.x + w
    masks = subcell_masks()
    rng = np.random.default_rng(7)
    kept = []
    for cls in range(8):
        n_p = start[cls + 1] - start[cls]
        for _ in range(60):
            # a chord between two points on the cell's faces
            ends = rng.random((2, 3))
            ends[np.arange(2), rng.integers(0, 3, 2)] = rng.integers(0, 2, 2)
            p0, d = ends[0], ends[1] - ends[0]
            union = np.zeros(masks.shape[-1], np.uint32)
            for c in _subcells_crossed(p0, d, SUBCELLS):
                union |= masks[(cls, *c)]
            for b in range(n_p):
                e = start[cls] + b
                rows = bary[tet[e]]
                lam0 = rows[:, :3] @ (p0 - centre[e]) + rows[:, 3]
                dl = rows[:, :3] @ d
                lo, hi = 0.0, 1.0
                for m in range(4):  # the segment part inside the tetrahedron
                    if dl[m] > 0:
                        lo = max(lo, -lam0[m] / dl[m])
                    elif dl[m] < 0:
                        hi = min(hi, -lam0[m] / dl[m])
                    elif lam0[m] < 0:
                        hi = -1.0
                if hi - lo > 1e-9:
                    assert (union[b >> 5] >> (b & 31)) & 1, (cls, b, p0, d)
            kept.append(sum(bin(int(w)).count("1") for w in union) / n_p)
    assert np.mean(kept) < 0.5
