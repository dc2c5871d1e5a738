"""3-vectors as tuples in compiled (numba) kernels: differences, products and lengths of
points without allocating arrays (a small array per operation costs more than the maths)."""

from __future__ import annotations

import math

import numba


@numba.njit(cache=True, inline="always")
def sub(u, v):
    """``u - v`` of two 3-tuples (or rows)."""
    return (u[0] - v[0], u[1] - v[1], u[2] - v[2])


@numba.njit(cache=True, inline="always")
def dot(u, v):
    """``u . v``."""
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@numba.njit(cache=True, inline="always")
def cross(u, v):
    """``u x v`` as a 3-tuple."""
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


@numba.njit(cache=True, inline="always")
def norm(u):
    """``|u|``."""
    return math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])


@numba.njit(cache=True, inline="always")
def row(p, i):
    """Row ``i`` of a ``(N, 3)`` array as a 3-tuple."""
    return (p[i, 0], p[i, 1], p[i, 2])
