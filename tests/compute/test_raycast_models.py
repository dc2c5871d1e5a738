"""Every spline model renders through ``sv.RayCaster`` (tetrahedral models on the NumPy path
until their kernels exist) and all of them show the same surface."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.raycast_reference import reference_raycast

from .helpers import cameras


@pytest.fixture(scope="module")
def blob():
    # a smooth field every model approximates well: the pictures must nearly coincide
    f = sv.testfunctions.TEST_FUNCTIONS["blob"]
    return sv.Volume.from_function(f, (17, 17, 17), f.domain), float(f.isovalue)


def test_all_models_render_the_same_surface(blob):
    vol, iso = blob
    cam = cameras(vol)[0]
    frames = {}
    for model in ("trilinear", "super-quadratic", "cubic-c1", "to-quadratic"):
        rc = sv.RayCaster(vol, model=model)
        rc.set_isovalue(iso)
        frames[model] = rc.render(cam, (48, 36))
        assert set(rc.stats) >= {"active_cells", "active_tets", "classify_s", "render_s",
                                 "device"}
        f = frames[model]
        assert f.hit.sum() > 120
        # hits are on the model's own isosurface
        vals = rc.spline.evaluate(f.position[f.hit])
        lo, hi = vol.finite_range
        assert np.max(np.abs(vals - iso)) <= 1e-5 * (hi - lo)
    base = frames["cubic-c1"].hit
    for model, f in frames.items():
        assert np.mean(f.hit == base) > 0.97, model


def test_numpy_path_is_the_reference(blob):
    vol, iso = blob
    rc = sv.RayCaster(vol, model="cubic-c1", device="numpy")
    rc.set_isovalue(iso)
    cam = cameras(vol)[2]
    planes = [(np.asarray(vol.bounds).mean(axis=1), (0, 0, 1))]
    f = rc.render(cam, (24, 18), clip_planes=planes)
    r = reference_raycast(rc.spline, cam, (24, 18), iso, clip_planes=planes)
    np.testing.assert_array_equal(f.hit, r.hit)
    np.testing.assert_array_equal(f.color, r.color)
    assert rc.stats["device"] == "numpy" and rc.stats["render_s"] > 0
