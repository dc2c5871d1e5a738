"""Visible-first classification (issue 12): the frames of a caster whose cells are classified
lazily by the rays, with per-cube caches carried across frames and isovalue changes, are the
frames of a caster that classified every cell first (``classify_all``)."""

import numpy as np
import pytest

from splineviz.compute.raycast import MAX_EPOCH, RayCaster, RayCastError
from splineviz.core.camera import Camera

from .helpers import HAVE_CL, marschner_lobb

needs_cl = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
SIZE = (96, 72)
MODELS = ["trilinear", "cubic-c1", "super-quadratic", "to-quadratic"]


@pytest.fixture(scope="module")
def ml():
    return marschner_lobb(25)


def _path(vol, iso):
    """(camera, isovalue) steps: close-ups of two corners, then the whole volume, with the
    isovalue changed and changed back, so that cached cubes are revisited at a new isovalue."""
    b = np.asarray(vol.bounds)
    c = b.mean(axis=1)
    r = np.linalg.norm(b[:, 1] - b[:, 0])

    def close(corner, d):
        target = c + 0.3 * (b[np.arange(3), corner] - c)
        d = np.asarray(d, float) / np.linalg.norm(d)
        return Camera(target + 0.45 * r * d, target, view_up=(0, 0, 1), view_angle=25.0)

    near_a = close([0, 0, 1], (-1.0, -1.3, 0.8))
    near_b = close([1, 1, 0], (1.2, 0.9, -0.7))
    whole = Camera(c + 1.6 * r * np.array([0.55, -0.7, 0.45]), c, view_angle=35.0)
    other = iso - 0.15
    return [(near_a, iso), (near_b, iso), (near_b, other), (whole, other), (near_a, iso),
            (whole, iso), (near_b, other)]


def _assert_same(frame, ref):
    np.testing.assert_array_equal(frame.hit, ref.hit)
    np.testing.assert_array_equal(frame.depth, ref.depth)
    np.testing.assert_array_equal(frame.normal[frame.hit], ref.normal[ref.hit])
    np.testing.assert_array_equal(frame.color, ref.color)


@needs_cl
@pytest.mark.parametrize("model", MODELS)
def test_visible_first_frames_equal_classify_all(ml, model):
    vol, iso = ml
    lazy = RayCaster(vol, model=model)
    full = RayCaster(vol, model=model)
    runs = []  # lazy cube counts per run of frames at one isovalue
    previous = None
    for cam, value in _path(vol, iso):
        lazy.set_isovalue(value)
        frame = lazy.render(cam, SIZE)
        full.set_isovalue(value)
        totals = full.classify_all()
        ref = full.render(cam, SIZE)
        assert ref.hit.sum() > 300  # every step shows the surface
        _assert_same(frame, ref)
        if lazy._family == "MODEL_TYPE6":
            # the lazy counts cover what the rays reached so far, never more than all
            cubes = lazy.stats["active_cells"]
            assert 0 < cubes <= full.stats["active_cells"] == np.count_nonzero(totals.relevant)
            assert lazy.stats["active_tets"] <= full.stats["active_tets"]
            if value == previous:
                runs[-1].append(cubes)
            else:
                runs.append([cubes])  # a new isovalue starts counting afresh
        previous = value
    if runs:
        # revealing new parts of the volume classifies more cubes at the same isovalue
        assert all(r == sorted(r) for r in runs) and any(r[-1] > r[0] for r in runs)


@needs_cl
def test_isovalue_changes_leave_no_stale_cubes(ml):
    # many changes wrap the 8-bit cache epoch: still no code of an older isovalue is used
    vol, iso = ml
    cam = _path(vol, iso)[3][0]
    lazy = RayCaster(vol, model="cubic-c1")
    for n in range(MAX_EPOCH + 20):
        lazy.set_isovalue(iso if n % 2 else iso - 0.15)
        if n % 50 == 0 or n > MAX_EPOCH:
            lazy.render(cam, (24, 18))
    assert 1 <= lazy._epoch <= MAX_EPOCH
    full = RayCaster(vol, model="cubic-c1")
    full.set_isovalue(lazy.isovalue)
    full.classify_all()
    _assert_same(lazy.render(cam, SIZE), full.render(cam, SIZE))
    # the same isovalue again keeps the cache
    epoch = lazy._epoch
    lazy.set_isovalue(lazy.isovalue)
    assert lazy._epoch == epoch


@needs_cl
def test_full_to_pool_grows_and_frames_stay_exact(ml):
    # a pool too small for one frame: rays that find it full work uncached, the pool grows
    # after the frame keeping its entries, and later frames fill it
    import pyopencl.array as cla

    vol, iso = ml
    rc = RayCaster(vol, model="to-quadratic")
    rc._pool_cap = 16
    rc._pool = cla.empty(rc._device.queue, 16 * rc._entry_words(), np.uint32)
    full = RayCaster(vol, model="to-quadratic")
    for cam, value in _path(vol, iso)[3:6]:
        rc.set_isovalue(value)
        full.set_isovalue(value)
        full.classify_all()
        _assert_same(rc.render(cam, SIZE), full.render(cam, SIZE))
        _assert_same(rc.render(cam, SIZE), full.render(cam, SIZE))  # from the cache
    assert rc._pool_cap > 200
    cells, _, used = rc._counts.get(queue=rc._device.queue)
    assert 0 < used <= rc._pool_cap and cells > used  # 8 cells per brick entry


@needs_cl
def test_set_isovalue_does_no_volume_pass(ml):
    vol, iso = ml
    rc = RayCaster(vol, model="cubic-c1")
    rc.set_isovalue(iso)
    assert rc.stats["active_cells"] == 0 and rc.stats["classified"] == "visible"
    rc.render(_path(vol, iso)[0][0], (32, 24))
    assert rc.stats["active_cells"] > 0


@needs_cl
def test_volume_too_big_for_the_device_is_refused(ml):
    vol, _ = ml
    rc = RayCaster(vol, model="cubic-c1")
    need = rc.device_bytes((4096, 4096, 4096), (4097, 4097, 4097))
    # the brick cache (a slot per 2^3 cubes and a pool for the reached ones) is small
    assert need["samples"] > 2**38 and 0 < need["classification cache"] < need["samples"] / 4
    with pytest.raises(RayCastError, match="GiB of device memory"):
        rc._check_device_memory((4096, 4096, 4096), (4097, 4097, 4097))
    rc._check_device_memory(vol.shape, rc._cells)  # what it already holds fits


@needs_cl
def test_volume_past_32_bit_sample_indices_is_cast_with_64_bit_offsets_or_refused(ml):
    # 1300^3 is 2.2e9 samples: 2.2 GB of uint8 fits an H200 easily, but 32-bit offsets wrap
    # past 2^31 - 1 (a wrong picture or a kernel fault, seen at 1536^3), so the kernels take
    # 64-bit offsets (OFFSET64) there; whether this device holds the volume is the caster's
    # limits' answer, not a guess from what PoCL reports
    vol, _ = ml
    shape = (1300, 1300, 1300)
    for model in ("trilinear", "cubic-c1"):
        rc = RayCaster(vol, model=model)
        limits = rc.limits(shape, itemsize=1)
        assert limits.samples > 2**31 - 1 and limits.offsets_64
        if limits.fits:
            rc._check_device_memory(shape, rc._grid(shape), itemsize=1)
        else:
            with pytest.raises(RayCastError, match="GiB of device memory"):
                rc._check_device_memory(shape, rc._grid(shape), itemsize=1)


@pytest.mark.parametrize("model", ["cubic-c1", "super-quadratic"])
def test_cube_program_is_determining_set_plus_rules(model):
    # the kernel's ordered program gives the cube coefficients of the core masks (and of
    # apply_rules) from the 27 stencil values, with fewer multiply-adds than the masks
    from splineviz.compute.raycast import _cube_program
    from splineviz.core.splines import type6_rules

    scheme = type6_rules.scheme(model)
    (ptr, cols, w), order = _cube_program(scheme)
    vals = np.random.default_rng(1).standard_normal(27)
    work = np.concatenate([vals, np.zeros(len(order))])
    for r in range(len(order)):
        work[27 + r] = work[cols[ptr[r]:ptr[r + 1]]] @ w[ptr[r]:ptr[r + 1]]
    got = np.empty(len(order))
    got[order] = work[27:]
    np.testing.assert_allclose(got, scheme.cube_masks @ vals, atol=1e-5)
    b_m = (scheme.determining_masks @ vals)[None]
    np.testing.assert_allclose(got, type6_rules.apply_rules(b_m, scheme)[0], atol=1e-5)
    assert len(cols) < 0.65 * np.count_nonzero(scheme.cube_masks)


@needs_cl
def test_to_cell_ranges_from_other_isovalues_give_the_same_frames(ml):
    # the isovalue-independent cell ranges, filled at other isovalues, skip cells whose range
    # excludes the new isovalue: the frames are those of a caster that never saw another
    vol, iso = ml
    path = _path(vol, iso)
    seasoned = RayCaster(vol, model="to-quadratic")
    for value in (iso - 0.3, iso + 0.2, iso - 0.15):
        seasoned.set_isovalue(value)
        for cam, _ in path[:4]:
            seasoned.render(cam, SIZE)
    ranges = seasoned._ranges.get(queue=seasoned._device.queue)
    known = np.count_nonzero(ranges != 0xFF00)
    assert known > 0.2 * ranges.size
    for value in (iso, iso - 0.15):
        seasoned.set_isovalue(value)
        fresh = RayCaster(vol, model="to-quadratic")
        fresh.set_isovalue(value)
        for cam, _ in path[3:6]:
            _assert_same(seasoned.render(cam, SIZE), fresh.render(cam, SIZE))
        assert seasoned.stats["active_tets"] == fresh.stats["active_tets"]
    # new data forget the ranges
    seasoned.set_volume(vol)
    assert np.all(seasoned._ranges.get(queue=seasoned._device.queue) == 0xFF00)
