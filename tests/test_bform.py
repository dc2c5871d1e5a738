"""Bernstein-Bezier toolkit (thesis chapter 3)."""

import numpy as np
import pytest

from splineviz.core import bform

RNG = np.random.default_rng(7)


def _poly(d):
    """A random polynomial of total degree d with its gradient and Hessian."""
    a = RNG.normal(size=6)

    def f(p):
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        return (a[0] + a[1] * x ** d + a[2] * y ** (d - 1) * z + a[3] * x * y ** (d - 1)
                + a[4] * z + a[5] * z ** d)

    def grad(p):
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        gy = a[2] * (d - 1) * y ** max(d - 2, 0) * z if d > 1 else 0 * x
        gxy = a[3] * (d - 1) * x * y ** max(d - 2, 0) if d > 1 else 0 * x
        return np.stack([a[1] * d * x ** (d - 1) + a[3] * y ** (d - 1),
                         gy + gxy,
                         a[2] * y ** (d - 1) + a[4] + a[5] * d * z ** (d - 1)], axis=1)

    return f, grad


def test_multi_indices_order_and_count():
    assert bform.multi_indices(2).tolist() == [
        [2, 0, 0, 0], [1, 1, 0, 0], [1, 0, 1, 0], [1, 0, 0, 1], [0, 2, 0, 0],
        [0, 1, 1, 0], [0, 1, 0, 1], [0, 0, 2, 0], [0, 0, 1, 1], [0, 0, 0, 2]]
    for d in range(4):
        n = (d + 1) * (d + 2) * (d + 3) // 6
        assert len(bform.multi_indices(d)) == bform.n_coefficients(d) == n


def test_barycentric_roundtrip_and_partition_of_unity():
    v = RNG.normal(size=(20, 4, 3))
    m = bform.barycentric_matrix(v)
    lam = RNG.dirichlet(np.ones(4), 20)
    x = np.einsum("nm,nmc->nc", lam, v)
    assert np.allclose(bform.barycentric(x, m), lam)
    for d in range(4):
        assert np.allclose(bform.bernstein_basis(lam, d).sum(axis=1), 1)  # eq. (3.10)


@pytest.mark.parametrize("d", [1, 2, 3])
def test_de_casteljau_values_and_gradient(d):
    f, grad = _poly(d)
    v = RNG.normal(size=(30, 4, 3))
    m = bform.barycentric_matrix(v)
    c = bform.bform_of_polynomial(f, v, d)
    lam = RNG.dirichlet(np.ones(4), 30)
    x = np.einsum("nm,nmc->nc", lam, v)
    assert np.allclose(bform.evaluate(c, lam), f(x))
    assert np.allclose(np.sum(c * bform.bernstein_basis(lam, d), axis=1), f(x))
    val, g = bform.value_gradient(c, lam, m)
    assert np.allclose(val, f(x)) and np.allclose(g, grad(x))


@pytest.mark.parametrize("d", [2, 3])
def test_directional_derivatives_and_hessian_match_finite_differences(d):
    f, _ = _poly(d)
    v = RNG.normal(size=(10, 4, 3))
    m = bform.barycentric_matrix(v)
    c = bform.bform_of_polynomial(f, v, d)
    lam = RNG.dirichlet(np.ones(4), 10)
    x = np.einsum("nm,nmc->nc", lam, v)
    u, w = RNG.normal(size=(2, 10, 3))
    du = bform.direction_barycentric(u, m)
    dw = bform.direction_barycentric(w, m)
    assert np.allclose(du.sum(axis=1), 0)
    e = 1e-4
    fd = (f(x + e * u) - f(x - e * u)) / (2 * e)
    assert np.allclose(bform.directional_derivative(c, lam, du), fd, atol=1e-6)
    fd2 = (f(x + e * u + e * w) - f(x + e * u - e * w) - f(x - e * u + e * w)
           + f(x - e * u - e * w)) / (4 * e * e)
    assert np.allclose(bform.directional_derivative(c, lam, du, dw), fd2, atol=1e-4)
    hess = bform.hessian(c, lam, m)
    assert np.allclose(np.einsum("na,nab,nb->n", u, hess, w), fd2, atol=1e-4)
    assert np.allclose(hess, np.swapaxes(hess, 1, 2))


def test_blossom_is_symmetric_multiaffine_and_diagonal():
    c = RNG.normal(size=(5, 20))  # cubic
    a, b, e = (RNG.dirichlet(np.ones(4), 5) for _ in range(3))
    assert np.allclose(bform.blossom(c, [a, b, e]), bform.blossom(c, [e, a, b]))
    assert np.allclose(bform.blossom(c, [a, a, a]), bform.evaluate(c, a))
    t = 0.3
    mix = (1 - t) * a + t * b
    assert np.allclose(bform.blossom(c, [mix, e, e]),
                       (1 - t) * bform.blossom(c, [a, e, e]) + t * bform.blossom(c, [b, e, e]))
    # partially applied blossom gives lower-degree B-coefficients
    assert bform.blossom(c, [a]).shape == (5, 10)
    with pytest.raises(ValueError):
        bform.blossom(c, [a, a, a, a])


def test_ray_blossoms_give_univariate_bernstein_form():
    """Restricted to a segment p(t) = (1-t) p0 + t p1, the cubic has Bernstein coefficients
    b(p0,p0,p0), b(p0,p0,p1), b(p0,p1,p1), b(p1,p1,p1) (§6.1.2)."""
    c = RNG.normal(size=(4, 20))
    p0, p1 = RNG.dirichlet(np.ones(4), 4), RNG.dirichlet(np.ones(4), 4)
    b = [bform.blossom(c, [p0] * (3 - i) + [p1] * i) for i in range(4)]
    for t in (0.0, 0.25, 0.8, 1.0):
        bern = sum(b[i] * [1, 3, 3, 1][i] * (1 - t) ** (3 - i) * t ** i for i in range(4))
        assert np.allclose(bern, bform.evaluate(c, (1 - t) * p0 + t * p1))
