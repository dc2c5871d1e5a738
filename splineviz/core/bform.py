"""Trivariate Bernstein-Bezier form on tetrahedra (thesis chapter 3).

Conventions
-----------
* A tetrahedron is a ``(4, 3)`` array of vertices ``[v0, v1, v2, v3]``.
* Barycentric coordinates are ``(..., 4)`` arrays; ``lam = x_h @ M.T`` with the homogeneous
  point ``x_h = (x, y, z, 1)`` and ``M = M_T^{-1}`` from :func:`barycentric_matrix`.
* A polynomial of degree ``d`` is stored by its ``n_d = (d+1)(d+2)(d+3)/6`` B-coefficients in
  the order of :func:`multi_indices` (lexicographically descending: for d = 2
  ``2000, 1100, 1010, 1001, 0200, 0110, 0101, 0020, 0011, 0002``); arrays of many polynomials
  are ``(N, n_d)``.
* Arguments of a blossom are barycentric *points* (coordinates summing to 1) or barycentric
  *directions* (coordinate differences of two points, summing to 0), see §3.4.2.

Everything is vectorised over the leading axis: one (tet, point) pair per row.
"""

from __future__ import annotations

from functools import cache
from math import factorial

import numpy as np

MAX_DEGREE = 3


@cache
def multi_indices(degree: int) -> np.ndarray:
    """All (i, j, k, l) with i + j + k + l = degree, lexicographically descending.

    Returns
    -------
    (n_d, 4) int array, read-only.
    """
    if degree < 0:
        raise ValueError(f"degree must be >= 0, got {degree}")
    rows = [
        (i, j, k, degree - i - j - k)
        for i in range(degree, -1, -1)
        for j in range(degree - i, -1, -1)
        for k in range(degree - i - j, -1, -1)
    ]
    out = np.array(rows, dtype=np.int64).reshape(-1, 4)
    out.flags.writeable = False
    return out


@cache
def index_map(degree: int) -> dict[tuple[int, int, int, int], int]:
    """Position of each multi-index (as a tuple) in :func:`multi_indices`."""
    return {tuple(int(v) for v in row): n for n, row in enumerate(multi_indices(degree))}


def n_coefficients(degree: int) -> int:
    """Number of B-coefficients of a trivariate polynomial of ``degree``."""
    return (degree + 1) * (degree + 2) * (degree + 3) // 6


@cache
def _reduction_table(degree: int) -> np.ndarray:
    """(n_{degree-1}, 4) positions of alpha + e_m among the degree-``degree`` indices."""
    lower = multi_indices(degree - 1)
    pos = index_map(degree)
    table = np.empty((len(lower), 4), dtype=np.int64)
    for a, alpha in enumerate(lower):
        for m in range(4):
            beta = list(int(v) for v in alpha)
            beta[m] += 1
            table[a, m] = pos[tuple(beta)]
    table.flags.writeable = False
    return table


def degree_of(n_coeffs: int) -> int:
    """Polynomial degree from the number of B-coefficients."""
    for d in range(0, MAX_DEGREE + 4):
        if n_coefficients(d) == n_coeffs:
            return d
    raise ValueError(f"{n_coeffs} is not the number of B-coefficients of any degree")


def barycentric_matrix(vertices: np.ndarray) -> np.ndarray:
    """M_T^{-1}: maps homogeneous points to barycentric coordinates (eq. 3.5).

    Parameters
    ----------
    vertices : (..., 4, 3) array
        Tetrahedra.

    Returns
    -------
    (..., 4, 4) array ``M`` with ``lam = M @ (x, y, z, 1)``. Column ``c < 3`` is the gradient
    of the barycentric coordinates with respect to world axis ``c``.
    """
    v = np.asarray(vertices, dtype=np.float64)
    homog = np.concatenate([v, np.ones(v.shape[:-1] + (1,))], axis=-1)  # (..., 4, 4) rows v_m
    # lam_m(v_n) = delta_mn  <=>  M @ homog.T = I
    return np.linalg.inv(np.swapaxes(homog, -1, -2))


def barycentric(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of ``(N, 3)`` points w.r.t. ``(N, 4, 4)`` (or ``(4, 4)``) M."""
    p = np.asarray(points, dtype=np.float64)
    m = np.asarray(matrix, dtype=np.float64)
    return np.einsum("...ij,...j->...i", m[..., :3], p) + m[..., 3]


def direction_barycentric(directions: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Barycentric direction (coordinates sum to 0) of ``(N, 3)`` world vectors."""
    return np.einsum("...ij,...j->...i", np.asarray(matrix)[..., :3], np.asarray(directions))


def domain_points(vertices: np.ndarray, degree: int) -> np.ndarray:
    """xi_ijkl = (i v0 + j v1 + k v2 + l v3) / d.

    Parameters
    ----------
    vertices : (..., 4, 3)

    Returns
    -------
    (..., n_d, 3)
    """
    idx = multi_indices(degree).astype(np.float64) / max(degree, 1)
    return np.einsum("nm,...mc->...nc", idx, np.asarray(vertices, dtype=np.float64))


def de_casteljau_step(coeffs: np.ndarray, arg: np.ndarray) -> np.ndarray:
    """One de Casteljau step (eq. 3.12): degree d coefficients -> degree d-1.

    Parameters
    ----------
    coeffs : (N, n_d) or (n_d,)
    arg : (N, 4) or (4,)
        Barycentric point or direction used in this step.

    Returns
    -------
    (N, n_{d-1})
    """
    c = np.asarray(coeffs, dtype=np.float64)
    a = np.asarray(arg, dtype=np.float64)
    table = _reduction_table(degree_of(c.shape[-1]))
    gathered = c[..., table]  # (..., n_{d-1}, 4)
    return np.einsum("...nm,...m->...n", gathered, a)


def blossom(coeffs: np.ndarray, args) -> np.ndarray:
    """The blossom b(a_1, ..., a_r, ...) with r <= d arguments (§3.4.2).

    With ``r < d`` arguments the result are the B-coefficients of degree ``d - r`` left after
    ``r`` de Casteljau steps; with ``r = d`` it is the blossom value.

    Parameters
    ----------
    coeffs : (N, n_d)
    args : sequence of (N, 4) arrays
        Barycentric points or directions, in any order (the blossom is symmetric).

    Returns
    -------
    (N, n_{d-r}) array; (N,) when r = d.
    """
    c = np.asarray(coeffs, dtype=np.float64)
    d = degree_of(c.shape[-1])
    if len(args) > d:
        raise ValueError(f"a degree-{d} blossom takes at most {d} arguments, got {len(args)}")
    for a in args:
        c = de_casteljau_step(c, a)
    return c[..., 0] if len(args) == d else c


def evaluate(coeffs: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """Value of the B-form at barycentric points: (N, n_d), (N, 4) -> (N,)."""
    d = degree_of(np.shape(coeffs)[-1])
    return blossom(coeffs, [lam] * d) if d else np.asarray(coeffs, np.float64)[..., 0]


def directional_derivative(coeffs: np.ndarray, lam: np.ndarray, *directions) -> np.ndarray:
    """D_{u_1} ... D_{u_r} p at ``lam`` (eq. 3.14): d!/(d-r)! b(u_1, .., u_r, lam, .., lam).

    Parameters
    ----------
    coeffs : (N, n_d)
    lam : (N, 4) barycentric points
    *directions : (N, 4) barycentric directions (see :func:`direction_barycentric`)

    Returns
    -------
    (N,)
    """
    d = degree_of(np.shape(coeffs)[-1])
    r = len(directions)
    if r > d:
        return np.zeros(np.shape(lam)[:-1])
    scale = factorial(d) / factorial(d - r)
    return scale * blossom(coeffs, list(directions) + [lam] * (d - r))


def value_gradient(coeffs: np.ndarray, lam: np.ndarray, matrix: np.ndarray):
    """Value and world gradient (eq. 3.16) from one shared de Casteljau pass.

    Parameters
    ----------
    coeffs : (N, n_d)
    lam : (N, 4)
    matrix : (N, 4, 4) or (4, 4)
        M_T^{-1} of each row's tetrahedron.

    Returns
    -------
    value : (N,)
    gradient : (N, 3)
    """
    c = np.asarray(coeffs, dtype=np.float64)
    d = degree_of(c.shape[-1])
    if d == 0:
        return c[..., 0], np.zeros(c.shape[:-1] + (3,))
    for _ in range(d - 1):
        c = de_casteljau_step(c, lam)
    # c: (N, 4) linear coefficients; p = sum_m c_m lam_m; grad = d sum_m c_m grad(lam_m)
    value = np.einsum("...m,...m->...", c, lam)
    grad = d * np.einsum("...m,...mc->...c", c, np.asarray(matrix)[..., :3])
    return value, grad


def hessian(coeffs: np.ndarray, lam: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """World Hessian of the B-form at barycentric points.

    Parameters
    ----------
    coeffs : (N, n_d)
    lam : (N, 4)
    matrix : (N, 4, 4) or (4, 4)

    Returns
    -------
    (N, 3, 3)
    """
    c = np.asarray(coeffs, dtype=np.float64)
    d = degree_of(c.shape[-1])
    if d < 2:
        return np.zeros(c.shape[:-1] + (3, 3))
    for _ in range(d - 2):
        c = de_casteljau_step(c, lam)
    # quadratic coefficients c_{e_m + e_n}; D_a D_b p = d(d-1) sum_{mn} c_{mn} A_ma A_nb
    pair = _quadratic_pairs()
    cq = c[..., pair]  # (N, 4, 4)
    grad_lam = np.asarray(matrix)[..., :3]
    return d * (d - 1) * np.einsum("...mn,...ma,...nb->...ab", cq, grad_lam, grad_lam)


@cache
def _quadratic_pairs() -> np.ndarray:
    pos = index_map(2)
    pair = np.empty((4, 4), dtype=np.int64)
    for m in range(4):
        for n in range(4):
            e = [0, 0, 0, 0]
            e[m] += 1
            e[n] += 1
            pair[m, n] = pos[tuple(e)]
    return pair


@cache
def _multinomials(degree: int) -> np.ndarray:
    return np.array(
        [factorial(degree) / np.prod([factorial(int(v)) for v in row])
         for row in multi_indices(degree)]
    )


def bernstein_basis(lam: np.ndarray, degree: int) -> np.ndarray:
    """B_ijkl(lam) = d!/(i!j!k!l!) lam0^i lam1^j lam2^k lam3^l.

    Parameters
    ----------
    lam : (N, 4)

    Returns
    -------
    (N, n_d)
    """
    lam = np.asarray(lam, dtype=np.float64)
    idx = multi_indices(degree)
    powers = np.prod(lam[..., None, :] ** idx, axis=-1)
    return _multinomials(degree) * powers


def bform_of_polynomial(func, vertices: np.ndarray, degree: int) -> np.ndarray:
    """B-coefficients of a polynomial of total degree <= ``degree`` on each tetrahedron.

    Interpolates ``func`` at the domain points, which is exact for polynomials of that degree.

    Parameters
    ----------
    func : callable
        ``func(points)`` with ``points`` of shape ``(M, 3)`` returning ``(M,)``.
    vertices : (T, 4, 3) or (4, 3)

    Returns
    -------
    (T, n_d) or (n_d,)
    """
    v = np.asarray(vertices, dtype=np.float64)
    single = v.ndim == 2
    v = v.reshape(-1, 4, 3)
    xi = domain_points(v, degree)  # (T, n, 3)
    values = np.asarray(func(xi.reshape(-1, 3)), dtype=np.float64).reshape(xi.shape[:2])
    # the collocation matrix at domain points is the same for every tetrahedron
    lam = multi_indices(degree).astype(np.float64) / max(degree, 1)
    coll = bernstein_basis(lam, degree)  # (n, n): row = domain point, column = basis
    coeffs = np.linalg.solve(coll, values.T).T
    return coeffs[0] if single else coeffs
