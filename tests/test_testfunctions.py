"""Closed-form test functions: derivatives agree with finite differences, known values."""

import numpy as np
import pytest

from splineviz.core.testfunctions import TEST_FUNCTIONS, barth, ml

RNG = np.random.default_rng(3)


@pytest.mark.parametrize("name", sorted(TEST_FUNCTIONS))
def test_derivatives_match_finite_differences(name):
    f = TEST_FUNCTIONS[name]
    p = RNG.uniform(-0.9, 0.9, size=(40, 3))
    e = 1e-5
    g, h = f.gradient(*p.T), f.hessian(*p.T)
    fd = np.stack([(f(*(p + e * d).T) - f(*(p - e * d).T)) / (2 * e) for d in np.eye(3)], -1)
    fd2 = np.stack([(f.gradient(*(p + e * d).T) - f.gradient(*(p - e * d).T)) / (2 * e)
                    for d in np.eye(3)], -1)
    assert np.allclose(g, fd, atol=1e-6 * (1 + np.abs(g).max()))
    assert np.allclose(h, fd2, atol=1e-6 * (1 + np.abs(h).max()))


def test_marschner_lobb_smooth_on_the_axis():
    # r = 0 is a removable singularity of the sqrt in the formula
    v = ml.derivatives(np.zeros(2), np.array([0.0, 1e-12]), np.array([0.3, 0.3]))
    assert np.all(np.isfinite(v.h)) and np.allclose(v.h[0], v.h[1], atol=1e-6)
    assert np.isclose(ml(0.0, 0.0, 0.0), (1 + 0.25 * (1 + np.cos(12 * np.pi))) / 2.5)


def test_barth_sextic_value():
    t = (1 + 5 ** 0.5) / 2
    x, y, z = 0.3, -0.2, 0.7
    want = 4 * (t * t * x * x - y * y) * (t * t * y * y - z * z) * (t * t * z * z - x * x) - (
        1 + 2 * t) * (x * x + y * y + z * z - 1) ** 2
    assert np.isclose(barth(x, y, z), want)


def test_directional_derivatives_subset():
    f = TEST_FUNCTIONS["fr"]
    p = RNG.uniform(-0.5, 0.5, size=(10, 3))
    d = f.derivatives(*p.T, [[1.0, 0.0, 0.0]])
    assert np.allclose(d.g[:, 0], f.gradient(*p.T)[:, 0])
    assert np.allclose(d.h[:, 0, 0], f.hessian(*p.T)[:, 0, 0])
