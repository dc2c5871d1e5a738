"""The OpenCL kernel family of the "tricubic-bspline" plugin (splineviz_bspline/bspline.cl)
against the plugin's own NumPy model and the NumPy reference ray caster."""

import time

import numpy as np
import pytest

import splineviz as sv
from splineviz import plugins
from splineviz.compute.raycast import RayCastError
from splineviz.core.raycast_reference import reference_raycast

from .helpers import HAVE_CL, cameras, compare_frames, marschner_lobb

pytestmark = [
    pytest.mark.skipif("bspline" not in {r.name for r in plugins.discover()},
                       reason="plugins/splineviz-bspline is not installed (./install.sh --dev)"),
    pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all"),
]

MODEL = "tricubic-bspline"
SIZE = (64, 48)


@pytest.fixture(scope="module", autouse=True)
def _plugins():
    plugins.ensure_loaded()


@pytest.fixture(scope="module")
def ml():
    return marschner_lobb(21)


@pytest.fixture(scope="module")
def noisy():
    # a rough field with thin, close-packed sheets: many cells with several roots per ray
    data = np.random.default_rng(5).normal(size=(9, 8, 10))
    return sv.Volume(data, spacing=(0.5, 1.25, 2.0), origin=(1.0, -2.0, 0.5)), 0.3


def _caster(vol, iso):
    rc = sv.RayCaster(vol, model=MODEL, device="cpu")
    rc.set_isovalue(iso)
    return rc


def test_the_plugin_model_renders_on_the_device(ml):
    vol, iso = ml
    rc = _caster(vol, iso)
    assert rc.stats["path"] == "opencl"
    assert rc.family.name == MODEL and not rc.family.bricks


@pytest.mark.parametrize("data", ["ml", "noisy"])
def test_hits_lie_on_the_spline_and_match_the_reference(data, request):
    vol, iso = request.getfixturevalue(data)
    rc = _caster(vol, iso)
    spline = rc.spline
    for cam in cameras(vol):
        f = rc.render(cam, SIZE)
        ref = reference_raycast(spline, cam, SIZE, iso)
        m = compare_frames(f, ref, spline, iso)
        assert f.hit.sum() > 200
        # s(x) = iso at the kernel's hits (the plugin's float64 NumPy evaluate)
        assert m["value_max"] < 2e-5, m
        assert m["hit_agreement"] > 0.995, m
        assert m["pos_ok"] > 0.99 and m["normal_ok"] > 0.99, m
        both = f.hit & ref.hit
        # the same first root: the depth agrees (no later root was taken)
        assert np.abs(f.depth[both] - ref.depth[both]).max() < 1e-4
        assert np.abs(f.color[both].astype(int) - ref.color[both]).max() <= 2
        # gradients: the normals are those of the NumPy gradient at the hits
        g = spline.gradient(f.position[f.hit])
        n = g / np.linalg.norm(g, axis=1, keepdims=True)
        assert np.abs(np.abs(np.sum(n * f.normal[f.hit], axis=1)) - 1).max() < 1e-4


def test_hessian_frames_are_the_numpy_hessian(ml):
    vol, iso = ml
    rc = _caster(vol, iso)
    f = rc.render(cameras(vol)[1], SIZE, hessian=True)
    p = f.position[f.hit]
    want = rc.spline.hessian(p)
    scale = np.abs(want).max()
    assert np.abs(f.hessian[f.hit] - want).max() < 1e-4 * scale
    np.testing.assert_allclose(f.gradient_norm[f.hit],
                               np.linalg.norm(rc.spline.gradient(p), axis=1), rtol=1e-4)
    assert np.isnan(f.hessian[~f.hit]).all()


def test_a_thin_feature_inside_one_cell_is_hit():
    """The isosurface just below a spike's maximum is a tiny closed surface around a sample:
    two roots about 0.004 voxel apart along the ray, between which plain sampling
    at any fixed step would have to land; the subdivision of the degree-9 restriction finds
    the first of them."""
    data = np.zeros((7, 7, 7))
    data[3, 3, 3] = 1.0
    vol = sv.Volume(data)
    spline = sv.build_spline(vol, model=MODEL)
    top = float(spline.evaluate(np.array([[3.0, 3.0, 3.0]]))[0])
    iso = top - 1e-5
    rc = _caster(vol, iso)
    # an odd frame: the middle pixel's ray passes through the maximum
    cam = sv.Camera((3.0 + 9.0, 3.0 - 13.0, 3.0 + 7.0), (3.0, 3.0, 3.0), view_angle=2.0)
    f = rc.render(cam, (5, 5))
    assert f.hit[2, 2]
    x = f.position[2, 2]
    assert np.linalg.norm(x - 3.0) < 0.05
    assert abs(float(spline.evaluate(x[None])[0]) - iso) < 1e-6
    d = (3.0 - np.asarray(cam.position)) / np.linalg.norm(3.0 - np.asarray(cam.position))
    # the ray is above iso over less than 0.01 voxel: x is its first root
    assert (spline.evaluate(np.array([x - 0.005 * d, x + 0.01 * d])) < iso).all()
    assert spline.evaluate((x + 0.002 * d)[None])[0] > iso


def test_64_bit_sample_offsets_give_the_same_frames(ml, monkeypatch):
    from splineviz.compute.raycast import caster

    vol, iso = ml
    cam = cameras(vol)[2]
    want = _caster(vol, iso).render(cam, SIZE, hessian=True)
    monkeypatch.setattr(caster, "MAX_SAMPLES", 1000)
    rc = _caster(vol, iso)
    assert rc.limits().offsets_64 and rc._prelude().startswith("#define offset_t long")
    got = rc.render(cam, SIZE, hessian=True)
    for name in ("hit", "color", "depth", "position", "normal", "hessian"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)


def test_the_kernel_is_refused_for_bricks(ml):
    from splineviz.compute.bricked import BrickedRayCaster

    vol, _ = ml
    with pytest.raises(RayCastError, match="cannot be rendered in bricks"):
        BrickedRayCaster(vol, model=MODEL)


@pytest.mark.bench
def test_frame_time_is_that_of_the_built_in_models():
    """A frame of the B-spline kernel against one of cubic-c1 on the same CT data and view
    (a ratio: both on the same device and machine load, interleaved, best of 5). On a busy
    2-core PoCL machine it was 1.5-3.3; the NumPy path it replaces was over 100."""
    from .helpers import DATA, load_volume

    if not (DATA / "tooth.nrrd").exists():
        pytest.skip("shared data not mounted")
    vol = load_volume("tooth.nrrd")
    lo, hi = vol.finite_range
    iso = lo + 0.35 * (hi - lo)
    cam = cameras(vol)[0]
    casters = {}
    for model in ("cubic-c1", MODEL):
        rc = sv.RayCaster(vol, model=model, device="cpu")
        rc.set_isovalue(iso)
        rc.render(cam, (64, 48))  # compile, classify the visible cells
        casters[model] = rc
    times = dict.fromkeys(casters, np.inf)
    for _ in range(5):
        for model, rc in casters.items():
            t = time.perf_counter()
            rc.render(cam, (320, 240))
            times[model] = min(times[model], time.perf_counter() - t)
    ratio = times[MODEL] / times["cubic-c1"]
    print(f"tricubic-bspline / cubic-c1 frame time: {ratio:.2f} ({times})")
    assert ratio < 10.0
