"""A new time step for the ray caster (issue 27): ``RayCaster.set_volume`` with samples of the
same shape and device type rewrites the samples and the octree in their buffers and keeps the
programs, tables and caches; its frames, exact and preview, are those of a fresh caster of
that step, bit for bit, whatever the caster cast before."""

import numpy as np
import pytest

from splineviz.compute.raycast import RayCaster
from splineviz.core.volume import Volume

from .helpers import HAVE_CL, cameras

needs_cl = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
MODELS = ["trilinear", "cubic-c1", "super-quadratic", "to-quadratic"]
EXACT, PREVIEW = (64, 48), (24, 18)
ISO = 128.0


@pytest.fixture(scope="module")
def steps(tmp_path_factory):
    """Four uint8 steps of the benchmark's deforming gyroid, 21^3 (odd: the last octree
    nodes hold one cell per axis)."""
    from splineviz.bench.time import make_series
    from splineviz.io.time_series import open_time_series

    series = open_time_series(make_series(tmp_path_factory.mktemp("steps"), 21, 4))
    return [series.step(k) for k in range(4)]


def _assert_same(frame, ref):
    for name in ("hit", "depth", "color"):
        np.testing.assert_array_equal(getattr(frame, name), getattr(ref, name), err_msg=name)
    np.testing.assert_array_equal(frame.normal[frame.hit], ref.normal[ref.hit])
    np.testing.assert_array_equal(frame.position[frame.hit], ref.position[ref.hit])


def _fresh(volume, model, cam):
    rc = RayCaster(volume, model=model)
    rc.set_isovalue(ISO)
    return rc.render(cam, EXACT), rc.render(cam, PREVIEW), rc


@needs_cl
@pytest.mark.parametrize("model", MODELS)
def test_step_change_gives_the_frames_of_a_fresh_caster(steps, model):
    cams = cameras(steps[0])
    rc = RayCaster(steps[0], model=model)
    rc.set_isovalue(ISO)
    for cam in cams:  # caches and cell ranges of step 0 filled
        rc.render(cam, EXACT)
    data = rc._data
    # forward, a step again, and back to the first: previews while playing, then the exact
    # frame after the pause
    for k in (1, 2, 2, 0):
        rc.set_volume(steps[k])
        assert rc._data is data  # the samples' buffer is rewritten, not replaced
        preview = rc.render(cams[1], PREVIEW)
        exact = rc.render(cams[1], EXACT)
        want_exact, want_preview, fresh = _fresh(steps[k], model, cams[1])
        _assert_same(preview, want_preview)
        _assert_same(exact, want_exact)
        assert exact.hit.sum() > 100
        np.testing.assert_array_equal(rc._bounds.get(), fresh._bounds.get())
        if model == "to-quadratic":  # the cell ranges of the old step are forgotten
            assert np.all(rc._ranges.get() == fresh._ranges.get())
    a, b = rc.classify_all(), fresh.classify_all()
    np.testing.assert_array_equal(a.cells, b.cells)
    if b.codes is not None:
        np.testing.assert_array_equal(a.codes, b.codes)
    assert rc.stats["active_cells"] == fresh.stats["active_cells"]


@needs_cl
@pytest.mark.parametrize("model", ["cubic-c1", "to-quadratic"])
def test_other_shape_or_type_is_uploaded_whole(steps, model):
    cam = cameras(steps[0])[0]
    rc = RayCaster(steps[0], model=model)
    rc.set_isovalue(ISO)
    rc.render(cam, EXACT)
    for volume in (Volume(np.asarray(steps[1].data)[:, 2:, 1:]),  # another shape
                   Volume(np.asarray(steps[1].data, np.float32) + 0.25)):  # float samples
        data = rc._data
        rc.set_volume(volume)
        assert rc._data is not data
        _assert_same(rc.render(cam, EXACT), _fresh(volume, model, cam)[0])


@needs_cl
@pytest.mark.parametrize("model", ["to-quadratic", "cubic-c1"])
def test_level_one_bounds_hold_every_cell(steps, model):
    """The octree's level-1 node (2^3 cells) bounds hold the value bounds of each of its
    cells: the TO node reads the union of its cells' data once, type-6 nodes their 2^3
    sample blocks."""
    from splineviz.compute.raycast.family import TO_WORDS
    from splineviz.compute.raycast.to_tables import class_points
    from splineviz.core.splines.boundary import pad_linear

    vol = steps[2]
    rc = RayCaster(vol, model=model)
    _, nx, ny, nz = rc._levels[0]
    level1 = rc._bounds.get()[:2 * nx * ny * nz].reshape(nx, ny, nz, 2).astype(np.float64)
    cx, cy, cz = rc._cells
    if model == "to-quadratic":
        ghost = rc.family.ghost_layers
        padded = pad_linear(vol.data, ghost)
        pts = class_points(2.0, TO_WORDS)
        start = pts["union_start"]
    else:
        padded = pad_linear(vol.data, 1)
    negmass = rc.negative_mass
    checked = 0
    for i in range(cx):
        for j in range(cy):
            for k in range(cz):
                if model == "to-quadratic":
                    c = (i & 1) << 2 | (j & 1) << 1 | (k & 1)
                    at = pts["union"][start[c]:start[c + 1]] + [i + ghost, j + ghost, k + ghost]
                    v = padded[tuple(at.T)]
                else:
                    v = padded[i:i + 3, j:j + 3, k:k + 3]
                lo, hi = v.min(), v.max()
                w = negmass * (hi - lo)
                node = level1[i >> 1, j >> 1, k >> 1]
                assert node[0] <= lo - w + 1e-3 and hi + w - 1e-3 <= node[1]
                checked += 1
    assert checked == cx * cy * cz


def test_node_union_lists_the_classes_data_once():
    from splineviz.compute.raycast.family import TO_WORDS
    from splineviz.compute.raycast.to_tables import class_points, node_union

    pts = class_points(2.0, TO_WORDS)
    start = pts["union_start"]
    want = {tuple(p + [c >> 2, c >> 1 & 1, c & 1])
            for c in range(8) for p in pts["union"][start[c]:start[c + 1]]}
    got = node_union(2.0, TO_WORDS)
    assert len(got) == len(want) == 125 < start[-1]
    assert {tuple(p) for p in got} == want
