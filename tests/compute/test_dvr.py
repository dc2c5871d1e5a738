"""Direct volume rendering: the OpenCL kernel against the NumPy reference, empty-space
skipping, clip planes and the embedding of isosurfaces and opaque geometry (issue 30)."""

import numpy as np
import pytest

from splineviz.compute.dvr import (
    MAX_LEAP,
    VolumeRenderer,
    block_bounds,
    depth_stop,
    isosurface_stop,
    leap_distances,
)
from splineviz.compute.raycast import RayCaster
from splineviz.core.camera import default_camera
from splineviz.core.dvr_reference import reference_dvr
from splineviz.core.testfunctions import ml
from splineviz.core.transfer_function import TransferFunction
from splineviz.core.volume import Volume

from .helpers import HAVE_CL

needs_cl = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
SIZE = (40, 32)


@pytest.fixture(scope="module")
def volume():
    return Volume.from_function(ml, (17, 17, 17), ml.domain)


@pytest.fixture(scope="module")
def tf():
    # transparent below 0.45: the low-valued corners of the volume are skipped
    return TransferFunction([0, 0.2, 0.3, 0.9, 1, 1, 0.8, 0.3],
                            [0, 0, 0.45, 0, 0.55, 0.6, 1, 0.1])


def _reference(rc, vr, cam, tf, **kw):
    vol = rc.volume
    return reference_dvr(rc.spline.value_gradient, vol.bounds, vol.spacing, cam, SIZE, tf,
                         vr.step, vr.shaded, preintegrated=vr.preintegrated, **kw)


@needs_cl
def test_preintegration_sees_a_thin_peak_between_samples(volume):
    """An opacity spike narrower than the value change per step: point samples step over it
    on many rays; pre-integrated segments count it (up to the linear value change they
    assume within a segment)."""
    thin = TransferFunction([0, 1, 1, 1, 1, 1, 1, 1], [0, 0, 0.48, 0, 0.5, 1, 0.52, 0, 1, 0])
    cam = default_camera(volume.bounds)
    coarse = {p: VolumeRenderer(volume, "cubic-c1", thin, device="cpu", step=2.0,
                                preintegrated=p).render(cam, SIZE) for p in (False, True)}
    fine = VolumeRenderer(volume, "cubic-c1", thin, device="cpu", step=0.05,
                          preintegrated=True).render(cam, SIZE)
    err = {p: np.abs(f.rgba[..., 3] - fine.rgba[..., 3]).mean() for p, f in coarse.items()}
    assert err[True] < 0.8 * err[False]  # measured: 0.025 against 0.036


@needs_cl
@pytest.mark.parametrize("model", ["trilinear", "cubic-c1", "super-quadratic"])
@pytest.mark.parametrize("shaded", [False, True])
@pytest.mark.parametrize("preintegrated", [False, True])
def test_kernel_matches_reference(volume, tf, model, shaded, preintegrated):
    vr = VolumeRenderer(volume, model, tf, device="cpu", step=0.5, shaded=shaded,
                        preintegrated=preintegrated)
    assert vr.stats["path"] == "opencl"
    assert vr.stats["skipped_blocks"] > 0
    cam = default_camera(volume.bounds)
    got = vr.render(cam, SIZE)
    want = _reference(vr.caster, vr, cam, tf)
    assert want.rgba[..., 3].max() > 0.5
    np.testing.assert_allclose(got.rgba, want.rgba, atol=1e-4)
    np.testing.assert_allclose(got.depth, want.depth, atol=1e-5)


@needs_cl
def test_clip_planes_cut_the_rendering(volume, tf):
    vr = VolumeRenderer(volume, "cubic-c1", tf, device="cpu")
    cam = default_camera(volume.bounds)
    planes = [((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))]
    got = vr.render(cam, SIZE, clip_planes=planes)
    want = _reference(vr.caster, vr, cam, tf, clip_planes=planes)
    np.testing.assert_allclose(got.rgba, want.rgba, atol=1e-4)
    assert not np.allclose(got.rgba, vr.render(cam, SIZE).rgba, atol=1e-3)


def test_leap_distances_are_chebyshev_distances_to_the_opaque_blocks():
    rng = np.random.default_rng(5)
    transparent = rng.random((9, 7, 11)) > 0.03
    got = leap_distances(transparent)
    opaque = np.argwhere(~transparent)
    idx = np.indices(transparent.shape).reshape(3, -1).T
    want = np.abs(idx[:, None, :] - opaque[None]).max(axis=2).min(axis=1)
    np.testing.assert_array_equal(got.ravel(), want)
    assert got.max() >= 3
    assert np.all(leap_distances(np.ones((3, 4, 5), bool)) == MAX_LEAP)


@needs_cl
@pytest.mark.parametrize("model", ["trilinear", "cubic-c1"])
def test_long_leaps_over_empty_space_keep_the_picture(model):
    """A blob far from the eye in an otherwise empty volume: rays leap many blocks at once and
    the picture is still the reference's (which marches every sample; a leap one block too
    far misses opacity by 0.035)."""
    x = np.linspace(0, 1, 41)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    data = np.exp(-((X - 0.3) ** 2 + (Y - 0.7) ** 2 + (Z - 0.3) ** 2) / 0.05)
    vol = Volume(data)
    tf = TransferFunction([0, 1, 0.5, 0.2, 1, 0.9, 0.9, 0.9], [0, 0, 0.3, 0, 0.6, 0.8, 1, 1])
    vr = VolumeRenderer(vol, model, tf, device="cpu", step=0.5)
    assert vr._leap.get().max() >= 5  # long leaps happen
    cam = default_camera(vol.bounds)
    size = (96, 96)
    got = vr.render(cam, size)
    want = reference_dvr(vr.caster.spline.value_gradient, vol.bounds, vol.spacing, cam, size,
                         tf, vr.step, vr.shaded)
    assert np.count_nonzero(want.rgba[..., 3] > 0.01) > 300
    np.testing.assert_allclose(got.rgba, want.rgba, atol=1e-4)


@pytest.mark.parametrize("model", [
    "trilinear",
    pytest.param("cubic-c1", marks=needs_cl),
    pytest.param("super-quadratic", marks=needs_cl)])
def test_block_bounds_hold_the_spline_and_are_tight(model):
    from splineviz.core.splines import build_spline

    rng = np.random.default_rng(3)
    data = rng.normal(size=(11, 9, 14))
    negmass = 0.0 if model == "trilinear" else RayCaster(
        Volume(data), model=model, device="cpu")._negmass
    lo, hi = block_bounds(data, negmass, 0 if model == "trilinear" else 1)
    assert lo.shape == (3, 3, 4)
    u = rng.uniform(0, np.array(data.shape) - 1, size=(20000, 3))
    u[:2000] = np.array(data.shape) - 1 - rng.uniform(0, 0.6, size=(2000, 3))  # the far faces
    v = build_spline(Volume(data), model).evaluate(u)
    b = np.minimum(np.floor(u).astype(int) // 4, np.array(lo.shape) - 1)
    assert np.all(lo[tuple(b.T)] <= v + 1e-12) and np.all(v <= hi[tuple(b.T)] + 1e-12)
    # tight: the trilinear bounds of an inner block are its samples' own min and max
    if model == "trilinear":
        assert lo[1, 1, 1] == data[4:9, 4:9, 4:9].min()
        assert hi[1, 1, 1] == data[4:9, 4:9, 4:9].max()


@needs_cl
@pytest.mark.parametrize("model", ["trilinear", "cubic-c1"])
def test_embedded_isosurface_keeps_its_hits(volume, model):
    """Behind a rendering too faint to reach the depth threshold, the frame's depth is the
    isosurface's alone, and the colour behind the volume is its shaded colour."""
    rc = RayCaster(volume, model=model, device="cpu")
    rc.set_isovalue(0.5)
    cam = default_camera(volume.bounds)
    iso = rc.render(cam, SIZE)
    faint = TransferFunction([0, 1, 1, 1, 1, 1, 1, 1], [0, 0.01, 1, 0.01])
    vr = VolumeRenderer(volume, model, faint, device="cpu")
    stop = isosurface_stop(iso, cam)
    got = vr.render(cam, SIZE, stop=stop)
    assert iso.hit.sum() > 100
    assert np.all(np.abs(got.depth[iso.hit] - iso.depth[iso.hit]) <= 1e-6)
    assert np.all(got.depth[~iso.hit] == 1.0)
    np.testing.assert_allclose(got.rgba[iso.hit, 3], 1.0, atol=1e-6)
    # the surface's colour shows through the faint volume in front of it
    diff = np.abs(got.color[iso.hit, :3].astype(int) - iso.color[iso.hit, :3].astype(int))
    assert np.percentile(diff, 50) <= 20
    want = _reference(vr.caster, vr, cam, faint, stop=stop)
    np.testing.assert_allclose(got.rgba, want.rgba, atol=1e-4)


@needs_cl
def test_opaque_sphere_hides_what_is_behind(volume, tf):
    """A sphere's depth buffer ends the rays: inside its silhouette the picture is the same
    whatever the volume holds behind the sphere."""
    cam = default_camera(volume.bounds)
    vr = VolumeRenderer(volume, "cubic-c1", tf, device="cpu")
    clip = cam.fit_clipping_range(volume.bounds)
    origin, dirs = cam.rays(SIZE)
    centre, radius = np.zeros(3), 0.5
    oc = origin - centre
    b = dirs @ oc
    disc = b**2 - (oc @ oc - radius**2)
    t_hit = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    inside = np.isfinite(t_hit)
    pts = origin + np.where(inside, t_hit, 0)[..., None] * dirs
    depth = np.where(inside, cam.window_depth(pts, clip), 1.0)
    color = np.zeros(SIZE[::-1] + (3,), np.uint8)
    color[inside] = (200, 30, 30)
    stop = depth_stop(depth, color, cam, clip)
    np.testing.assert_allclose(stop[0][inside], t_hit[inside], rtol=1e-9)
    got = vr.render(cam, SIZE, stop=stop)
    # the same volume with everything behind the sphere's centre plane changed
    data = volume.data.copy()
    far = np.einsum("ijkl,l->ijk", np.stack(np.meshgrid(
        *[np.linspace(-1, 1, 17)] * 3, indexing="ij"), -1) - origin, cam.basis()[2])
    data[far > np.linalg.norm(origin) + radius + 0.1] = 0.9
    other = VolumeRenderer(Volume(data, spacing=volume.spacing, origin=volume.origin),
                           "cubic-c1", tf, device="cpu").render(cam, SIZE, stop=stop)
    assert inside.sum() > 50
    np.testing.assert_array_equal(got.color[inside], other.color[inside])
    assert np.all(got.rgba[inside, 3] >= 1.0 - 1e-6)
    assert not np.array_equal(got.color[~inside], other.color[~inside])
