"""The first-party "tricubic-bspline" model plugin, reached only through the entry point."""

import numpy as np
import pytest

import splineviz as sv
from splineviz import plugins

pytestmark = pytest.mark.skipif(
    "bspline" not in {r.name for r in plugins.discover()},
    reason="plugins/splineviz-bspline is not installed (run ./install.sh --dev)")

RNG = np.random.default_rng(11)


@pytest.fixture(scope="module")
def spline():
    data = RNG.normal(size=(7, 6, 8))
    vol = sv.Volume(data, spacing=(0.5, 1.25, 2.0), origin=(1.0, -2.0, 0.5))
    return sv.build_spline(vol, model="tricubic-bspline"), vol


def _inside(vol, n):
    lo = np.array([b[0] for b in vol.bounds])
    hi = np.array([b[1] for b in vol.bounds])
    return lo + RNG.uniform(0.02, 0.98, size=(n, 3)) * (hi - lo)


def test_values_match_scipy_map_coordinates(spline):
    from scipy.ndimage import map_coordinates

    s, vol = spline
    p = _inside(vol, 200)
    idx = vol.world_to_index(p)
    ref = map_coordinates(np.asarray(vol.data, float), idx.T, order=3, mode="mirror")
    np.testing.assert_allclose(s.evaluate(p), ref, atol=1e-10)


def test_interpolates_the_samples(spline):
    s, vol = spline
    ijk = np.array([[0, 0, 0], [6, 5, 7], [3, 2, 4], [1, 5, 0]])
    np.testing.assert_allclose(s.evaluate(vol.index_to_world(ijk)),
                               vol.data[tuple(ijk.T)], atol=1e-5)


def test_gradient_and_hessian_are_exact_derivatives(spline):
    s, vol = spline
    p = _inside(vol, 40)
    h = 1e-5
    g, H = s.gradient(p), s.hessian(p)
    for a in range(3):
        e = np.zeros(3)
        e[a] = h
        fd = (s.evaluate(p + e) - s.evaluate(p - e)) / (2 * h)
        np.testing.assert_allclose(g[:, a], fd, rtol=1e-5, atol=1e-6)
        fdg = (s.gradient(p + e) - s.gradient(p - e)) / (2 * h)
        np.testing.assert_allclose(H[:, :, a], fdg, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(H, H.transpose(0, 2, 1), atol=1e-12)


def test_second_derivatives_are_continuous_across_cells(spline):
    """C2: the Hessian from the two cells meeting at a grid plane agrees there."""
    s, vol = spline
    p = _inside(vol, 20)
    p[:, 0] = vol.origin[0] + 3 * vol.spacing[0]  # on the plane i = 3
    eps = 1e-9
    left = s.hessian(p - [eps, 0, 0])
    right = s.hessian(p + [eps, 0, 0])
    np.testing.assert_allclose(left, right, atol=1e-6)
