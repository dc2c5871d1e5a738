"""The compiled type-6 spline kernels of the spline front against the vectorised NumPy
evaluation they replace: values and gradients, Newton projection, the one-sheet test of
triangles and the sheet gaps."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import splineviz as sv
from splineviz.core.isosurface import project_to_isosurface
from splineviz.pointcloud import spline_kernels as sk
from splineviz.pointcloud import spline_mesh as sm

RNG_SEED = 14


def _volume():
    # rough data, anisotropic spacing and an offset origin: every index-space step counts
    rng = np.random.default_rng(RNG_SEED)
    return sv.Volume(rng.normal(size=(9, 8, 7)), (0.7, 1.0, 1.3), (1.0, -2.0, 0.5))


@pytest.mark.parametrize("model", ["cubic-c1", "super-quadratic"])
def test_values_and_gradients(model):
    spline = sv.build_spline(_volume(), model)
    fast = sk.compiled(spline)
    assert fast is not None and sk.compiled(spline) is fast  # built once
    lo = np.array([b[0] for b in spline.bounds])
    hi = np.array([b[1] for b in spline.bounds])
    rng = np.random.default_rng(RNG_SEED)
    p = lo + rng.random((3000, 3)) * (hi - lo)
    # grid points, the faces of the cubes and tetrahedra, the box's faces and a rounding error
    # outside them (clamped in, like the NumPy path)
    p[:200] = lo + np.round((p[:200] - lo) / spline.volume.spacing * 2) / 2 * \
        np.asarray(spline.volume.spacing)
    p[200:300, 0] = hi[0]
    p[300:400, 2] = lo[2] - 1e-12
    value, grad = fast.value_gradient(p)
    v_ref, g_ref = spline.value_gradient(p)
    scale = np.abs(v_ref).max()
    np.testing.assert_allclose(value, v_ref, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(grad, g_ref, rtol=0, atol=1e-12 * scale)


def test_not_covered_models_fall_back():
    assert sk.compiled(sv.build_spline(_volume(), "trilinear")) is None


def _sphere_spline():
    # cubic-c1 reproduces x^2 + y^2 + z^2 up to 3/4: the isosurface 100.75 is the sphere of
    # radius 10
    vol = sv.Volume.from_function(lambda x, y, z: x * x + y * y + z * z, (24, 24, 24),
                                  ((-11.5, 11.5),) * 3)
    return sv.build_spline(vol, "cubic-c1"), 100.75


def test_projection_matches_newton_steps():
    spline, iso = _sphere_spline()
    rng = np.random.default_rng(RNG_SEED)
    d = rng.normal(size=(500, 3))
    start = (10.0 + rng.uniform(-2.0, 2.0, (500, 1))) * d / np.linalg.norm(d, axis=1)[:, None]
    start[:5, 2] = 11.5  # on a face of the box: the point slides within it
    for steps in (1, 3, 8):
        x, n = sm.project_onto(spline, start, iso, steps)
        x_ref, n_ref = project_to_isosurface(spline, start, iso, steps=steps)
        np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-10)
        np.testing.assert_allclose(n, n_ref, rtol=0, atol=1e-10)
    np.testing.assert_allclose(x[:, 2][:5], 11.5)
    # with a tolerance every point stops on its own once within it
    lo, hi = spline.volume.finite_range
    tol = 1e-9 * (hi - lo)
    x, n = sm.project_onto(spline, start[5:], iso, 30, tol)
    assert np.abs(spline.evaluate(x) - iso).max() <= tol
    np.testing.assert_allclose(n, -x / np.linalg.norm(x, axis=1)[:, None], atol=1e-9)


def _triangles(rng, count, radius, size):
    """Triangles of side ~``size`` about points on a sphere of ``radius``, in every
    orientation and at every height: on the surface, off it, across it."""
    d = rng.normal(size=(count, 3))
    centre = radius * d / np.linalg.norm(d, axis=1)[:, None]
    return centre[:, None, :] + size * rng.normal(size=(count, 3, 3))


def test_one_sheet_test_matches_the_vectorised_one():
    # (r - 10)^2 = 0.5625: two concentric spheres 1.5 apart (radii 9.25 and 10.75)
    vol = sv.Volume.from_function(lambda x, y, z: (np.sqrt(x * x + y * y + z * z) - 10.0) ** 2,
                                  (32, 32, 32), ((-15.5, 15.5),) * 3)
    spline = sv.build_spline(vol, "cubic-c1")
    iso = 0.5625
    rng = np.random.default_rng(RNG_SEED)
    pts, _nrm, _cell = sm.surface_samples(spline, iso)
    # corners on the surface (the front's candidates) of a few grid steps, some of them on
    # both spheres
    _, near = cKDTree(pts).query(pts[rng.integers(0, len(pts), 1000)], k=40)
    corners = near[np.arange(1000)[:, None], np.sort(rng.integers(0, 40, (1000, 3)), axis=1)]
    tri = np.concatenate([
        pts[corners],
        _triangles(rng, 800, 10.75, 0.8), _triangles(rng, 800, 9.25, 2.5),
        _triangles(rng, 300, 10.0, 6.0)])
    for slack in (0.0, sm.HOLE_SLACK):
        ok = sm.triangles_on_surface(spline, iso, tri, slack)
        ref = sm._on_surface_numpy(spline, iso, tri, slack)
        np.testing.assert_array_equal(ok, ref)
        assert 0.05 < ok.mean() < 0.95  # both answers are tested


def test_sheet_gaps_match_the_vectorised_ones():
    vol = sv.Volume.from_function(lambda x, y, z: (np.sqrt(x * x + y * y + z * z) - 10.0) ** 2,
                                  (32, 32, 32), ((-15.5, 15.5),) * 3)
    spline = sv.build_spline(vol, "cubic-c1")
    iso = 0.5625
    pts, nrm, _cell = sm.surface_samples(spline, iso)
    rng = np.random.default_rng(RNG_SEED)
    # some samples tilted: the rays then meet the other sphere at varied distances or not
    tilt = nrm + 0.8 * rng.normal(size=nrm.shape)
    tilt /= np.linalg.norm(tilt, axis=1)[:, None]
    for reach in (1.0, 5.0):
        step = float(np.min(spline.volume.spacing))
        ts = np.arange(sm.GAP_START * step, reach + 0.5 * sm.GAP_STEP * step,
                       sm.GAP_STEP * step)
        for normals in (nrm, tilt):
            gaps = sm.sheet_gaps(spline, iso, pts, normals, reach)
            ref = sm._sheet_gaps_numpy(spline, iso, pts, normals, reach, ts)
            np.testing.assert_array_equal(gaps, ref)
