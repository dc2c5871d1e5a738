"""Compiled (numba) evaluation of type-6 splines (cubic-c1, super-quadratic) for the advancing
front on a spline isosurface (:mod:`.spline_mesh`).

The front asks the spline small questions one at a time: does this candidate triangle lie on
one sheet of ``s = iso`` (a few dozen probes), where does this batch of predicted apexes land
on the surface (Newton steps). Through the vectorised NumPy evaluation
(:meth:`~splineviz.core.splines.type6_spline.Type6Spline.index_derivatives`: locate, sort by
tetrahedron, 24 gathers, de Casteljau steps) each such call paid ~0.3 ms of fixed cost, most of
the front's time on the bonsai; here one point costs about a microsecond.

The arithmetic is that of the NumPy path (thesis §4.4, eq. 4.3 for the B-coefficients of the
generic tetrahedron around a point, eq. 3.12 / 3.16 for value and gradient from the de
Casteljau steps); only the order of some sums differs, so results agree to rounding.

Conventions: points ``(N, 3)`` float64 world coordinates; a spline is passed to the kernels as
the tuple :attr:`CompiledSpline.params`.
"""

from __future__ import annotations

import math
import weakref

import numba
import numpy as np

from splineviz.core import bform
from splineviz.core.partitions import type6
from splineviz.core.splines.type6_spline import GHOST_LAYERS, Type6Spline


@numba.njit(cache=True)
def _value_gradient(params, x, y, z, work, out):
    """Value and world gradient of the spline at ``(x, y, z)`` into ``out (4,)``.

    ``work (2 n_d + 4,)`` is scratch space: coefficients, their reduction, barycentric
    coordinates.
    """
    (flat, pstride, stencil, used, compact, bary, lookup, tables, nrows, umax, origin,
     spacing) = params
    p = (x, y, z)
    local = np.empty(3)
    cube = np.empty(3, dtype=np.int64)
    for d in range(3):
        # as Spline._run: index space, clamped into the box (a rounding error outside)
        u = (p[d] - origin[d]) / spacing[d]
        u = min(max(u, 0.0), umax[d])
        c = math.floor(u + 0.5)
        cube[d] = int(c)
        local[d] = u - c
    # type6.locate: the pyramid by the largest |local| (first of equals, as argmax), the
    # tetrahedron by the larger of the two others (cyclic order after it)
    m0, m1, m2 = abs(local[0]), abs(local[1]), abs(local[2])
    a = 0
    if m1 > m0:
        a = 1
    if m2 > max(m0, m1):
        a = 2
    b1, b2 = (a + 1) % 3, (a + 2) % 3
    b = b1 if abs(local[b1]) >= abs(local[b2]) else b2
    t = lookup[a, 1 if local[a] < 0 else 0, b, 1 if local[b] < 0 else 0]
    base = (cube[0] + GHOST_LAYERS) * pstride[0] + (cube[1] + GHOST_LAYERS) * pstride[1] + \
        (cube[2] + GHOST_LAYERS) * pstride[2]
    n_d = compact.shape[1]
    k = compact.shape[2]
    c = work[:n_d]
    nxt = work[n_d:2 * n_d]
    lam = work[2 * n_d:2 * n_d + 4]
    for r in range(n_d):
        c[r] = 0.0
    # eq. (4.3): the tetrahedron's B-coefficients are mask products of the data it uses
    for j in range(k):
        f = flat[base + stencil[used[t, j]]]
        for r in range(n_d):
            c[r] += compact[t, r, j] * f
    for m in range(4):
        lam[m] = bary[t, m, 0] * local[0] + bary[t, m, 1] * local[1] + \
            bary[t, m, 2] * local[2] + bary[t, m, 3]
    degree = tables.shape[0] + 1
    # de Casteljau steps (eq. 3.12) down to the linear coefficients
    for s in range(degree - 1):
        for r in range(nrows[s]):
            nxt[r] = c[tables[s, r, 0]] * lam[0] + c[tables[s, r, 1]] * lam[1] + \
                c[tables[s, r, 2]] * lam[2] + c[tables[s, r, 3]] * lam[3]
        for r in range(nrows[s]):
            c[r] = nxt[r]
    out[0] = c[0] * lam[0] + c[1] * lam[1] + c[2] * lam[2] + c[3] * lam[3]
    # eq. (3.16): grad p = d sum_m c_m grad(lam_m), then the chain rule for the spacing
    for d in range(3):
        out[1 + d] = degree * (c[0] * bary[t, 0, d] + c[1] * bary[t, 1, d] +
                               c[2] * bary[t, 2, d] + c[3] * bary[t, 3, d]) / spacing[d]


@numba.njit(cache=True)
def value_gradient(params, points, n_work):
    """Values ``(N,)`` and gradients ``(N, 3)`` at ``points (N, 3)``."""
    work = np.empty(n_work)
    res = np.empty(4)
    value = np.empty(len(points))
    grad = np.empty((len(points), 3))
    for i in range(len(points)):
        _value_gradient(params, points[i, 0], points[i, 1], points[i, 2], work, res)
        value[i] = res[0]
        grad[i, 0], grad[i, 1], grad[i, 2] = res[1], res[2], res[3]
    return value, grad


@numba.njit(cache=True)
def project(params, points, iso, steps, tol, lo, hi, step_limit, n_work):
    """Newton projection onto ``s = iso`` of each point (see
    :func:`splineviz.core.isosurface.project_to_isosurface`), each point stopping on its own
    once ``|s - iso| <= tol`` (``tol < 0``: always ``steps`` steps).

    Returns
    -------
    points : (N, 3), normals : (N, 3) unit ``-grad s / |grad s|``, zero where it vanishes
    """
    work = np.empty(n_work)
    res = np.empty(4)
    out = np.empty_like(points)
    normals = np.zeros_like(points)
    face = 1e-9 * max(hi[0] - lo[0], max(hi[1] - lo[1], hi[2] - lo[2]))
    x = np.empty(3)
    free = np.empty(3)
    delta = np.empty(3)
    for i in range(len(points)):
        for d in range(3):
            x[d] = points[i, d]
            # a point on a face of the box slides within that face
            free[d] = 0.0 if (abs(x[d] - lo[d]) < face or abs(x[d] - hi[d]) < face) else 1.0
        current = False  # whether res holds the gradient at x
        for _ in range(steps):
            _value_gradient(params, x[0], x[1], x[2], work, res)
            f = res[0] - iso
            if tol >= 0 and abs(f) <= tol:
                current = True
                break
            g2 = 0.0
            for d in range(3):
                g2 += (res[1 + d] * free[d]) ** 2
            norm2 = 0.0
            for d in range(3):
                delta[d] = f / g2 * res[1 + d] * free[d] if g2 > 1e-30 else 0.0
                norm2 += delta[d] * delta[d]
            # never further than half a voxel: a point belongs to the sheet it started on
            scale = min(1.0, step_limit / max(math.sqrt(norm2), 1e-300))
            for d in range(3):
                x[d] = min(max(x[d] - delta[d] * scale, lo[d]), hi[d])
        if not current:
            _value_gradient(params, x[0], x[1], x[2], work, res)
        gn = math.sqrt(res[1] * res[1] + res[2] * res[2] + res[3] * res[3])
        for d in range(3):
            out[i, d] = x[d]
            if gn > 0:
                normals[i, d] = -res[1 + d] / gn
    return out, normals


@numba.njit(cache=True)
def on_surface(params, tri, iso, step, slack, spacing_frac, max_div, deviation, crossing,
               floor, cos_turn, n_work):
    """The one-sheet test of :func:`splineviz.pointcloud.spline_mesh.triangles_on_surface`
    for triangles ``tri (T, 3, 3)``; its constants are the arguments (``spacing_frac`` is
    PROBE_SPACING, ``deviation`` SURFACE_DEVIATION, ``crossing`` SURFACE_CROSSING, ``floor``
    PROBE_FLOOR in grid steps, ``cos_turn`` the cosine of MAX_CORNER_TURN).

    A triangle stops at its first failing probe (the answer is the same).

    Returns
    -------
    (T,) bool
    """
    work = np.empty(n_work)
    res = np.empty(4)
    ok = np.ones(len(tri), dtype=np.bool_)
    gn = np.empty((3, 3))
    for t in range(len(tri)):
        longest = 0.0
        for c in range(3):
            e = 0.0
            for d in range(3):
                e += (tri[t, c, d] - tri[t, c - 1, d]) ** 2
            longest = max(longest, math.sqrt(e))
        # corner normals less than MAX_CORNER_TURN apart
        for c in range(3):
            _value_gradient(params, tri[t, c, 0], tri[t, c, 1], tri[t, c, 2], work, res)
            norm = max(math.sqrt(res[1] * res[1] + res[2] * res[2] + res[3] * res[3]), 1e-300)
            for d in range(3):
                gn[c, d] = res[1 + d] / norm
        for c in range(3):
            e = (c + 1) % 3
            if not gn[c, 0] * gn[e, 0] + gn[c, 1] * gn[e, 1] + gn[c, 2] * gn[e, 2] >= cos_turn:
                ok[t] = False
        if not ok[t]:
            continue
        div = int(min(max(math.ceil(longest / (spacing_frac * step)), 2.0), max_div))
        dev = max(deviation * longest, max(floor * step, slack * step))
        cross = max(crossing * longest, floor * step)
        above, below = False, False
        for i in range(div + 1):
            for j in range(div + 1 - i):
                k = div - i - j
                if i == div or j == div or k == div:
                    continue  # the corners lie on the surface
                w0, w1, w2 = i / div, j / div, k / div
                _value_gradient(params,
                                w0 * tri[t, 0, 0] + w1 * tri[t, 1, 0] + w2 * tri[t, 2, 0],
                                w0 * tri[t, 0, 1] + w1 * tri[t, 1, 1] + w2 * tri[t, 2, 1],
                                w0 * tri[t, 0, 2] + w1 * tri[t, 1, 2] + w2 * tri[t, 2, 2],
                                work, res)
                # first-order distance; a vanishing gradient makes it infinite (untrusted)
                g = max(math.sqrt(res[1] * res[1] + res[2] * res[2] + res[3] * res[3]),
                        1e-300)
                dist = (res[0] - iso) / g
                above = above or dist > cross
                below = below or dist < -cross
                if not abs(dist) <= dev or (above and below):
                    ok[t] = False
                    break
            if not ok[t]:
                break
    return ok


@numba.njit(cache=True)
def gaps(params, points, normals, iso, ts, reach, lo, hi, n_work):
    """:func:`splineviz.pointcloud.spline_mesh.sheet_gaps` marched point by point: the first
    ``ts`` along ``+normal`` with ``s >= iso`` or along ``-normal`` with ``s <= iso``, inside
    the box ``lo``..``hi``; ``reach`` where there is none. Returns ``(N,)``."""
    work = np.empty(n_work)
    res = np.empty(4)
    out = np.full(len(points), reach)
    for i in range(len(points)):
        for sign in (1.0, -1.0):
            for it in range(len(ts)):
                t = ts[it]
                if t >= out[i]:
                    break  # a nearer sheet is known already
                q0 = points[i, 0] + sign * t * normals[i, 0]
                q1 = points[i, 1] + sign * t * normals[i, 1]
                q2 = points[i, 2] + sign * t * normals[i, 2]
                if not (lo[0] <= q0 <= hi[0] and lo[1] <= q1 <= hi[1] and
                        lo[2] <= q2 <= hi[2]):
                    continue
                _value_gradient(params, q0, q1, q2, work, res)
                if sign * (res[0] - iso) >= 0:
                    out[i] = t
                    break
    return out


class CompiledSpline:
    """A type-6 spline in the layout of the compiled kernels.

    Parameters
    ----------
    spline : Type6Spline
    """

    def __init__(self, spline: Type6Spline):
        used, compact = spline._compact
        degree = spline.degree
        n_max = bform.n_coefficients(degree - 1)
        tables = np.zeros((max(degree - 1, 1), n_max, 4), dtype=np.int64)
        nrows = np.zeros(max(degree - 1, 1), dtype=np.int64)
        for s in range(degree - 1):
            table = bform._reduction_table(degree - s)
            tables[s, :len(table)] = table
            nrows[s] = len(table)
        vol = spline.volume
        #: the kernels' view of the spline (see :func:`_value_gradient`)
        self.params = (np.ascontiguousarray(spline.padded, dtype=np.float64).ravel(),
                       np.ascontiguousarray(spline._pad_strides, dtype=np.int64),
                       np.ascontiguousarray(spline._stencil, dtype=np.int64),
                       np.ascontiguousarray(used, dtype=np.int64),
                       np.ascontiguousarray(compact, dtype=np.float64),
                       np.ascontiguousarray(type6.barycentric_matrices(), dtype=np.float64),
                       np.ascontiguousarray(type6.TET_LOOKUP, dtype=np.int64),
                       tables, nrows,
                       np.asarray(vol.shape, dtype=np.float64) - 1.0,
                       np.asarray(vol.origin, dtype=np.float64),
                       np.asarray(vol.spacing, dtype=np.float64))
        self.n_work = 2 * compact.shape[1] + 4
        self.lo = np.array([b[0] for b in spline.bounds], dtype=np.float64)
        self.hi = np.array([b[1] for b in spline.bounds], dtype=np.float64)
        self.step = float(np.min(vol.spacing))

    def value_gradient(self, points):
        """Values ``(N,)`` and world gradients ``(N, 3)`` at ``points (N, 3)``."""
        return value_gradient(self.params, _points(points), self.n_work)

    def project(self, points, iso, steps, tol=None):
        """Newton projection onto ``s = iso``: ``(N, 3)`` points and unit normals ``(N, 3)``
        (see :func:`project`)."""
        return project(self.params, _points(points), float(iso), int(steps),
                       -1.0 if tol is None else float(tol), self.lo, self.hi,
                       0.5 * self.step, self.n_work)

    def on_surface(self, triangles, iso, slack, spacing_frac, max_div, deviation, crossing,
                   floor, max_turn):
        """:func:`on_surface` of triangles ``(T, 3, 3)``: ``(T,)`` bool."""
        tri = np.ascontiguousarray(np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3))
        return on_surface(self.params, tri, float(iso), self.step, float(slack),
                          float(spacing_frac), int(max_div), float(deviation), float(crossing),
                          float(floor), float(math.cos(max_turn)), self.n_work)

    def gaps(self, points, normals, iso, ts, reach):
        """:func:`gaps`: ``(N,)`` distances to the next sheet."""
        return gaps(self.params, _points(points), _points(normals), float(iso),
                    np.ascontiguousarray(ts, dtype=np.float64), float(reach), self.lo, self.hi,
                    self.n_work)


def _points(points):
    return np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))


_COMPILED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def compiled(spline) -> CompiledSpline | None:
    """The compiled form of ``spline`` (built once per spline), or None for a model the
    kernels do not cover (not a type-6 spline, or one that evaluates differently)."""
    cls = type(spline)
    if not isinstance(spline, Type6Spline) or \
            cls.index_derivatives is not Type6Spline.index_derivatives or \
            cls._sorted_coefficients is not Type6Spline._sorted_coefficients or \
            spline.degree < 2:
        return None
    found = _COMPILED.get(spline)
    if found is None:
        found = _COMPILED[spline] = CompiledSpline(spline)
    return found


def compile_kernels() -> None:
    """Compile the kernels into numba's on-disk cache (install.sh runs this once)."""
    import splineviz as sv

    i, j, k = np.indices((4, 4, 4))
    spline = compiled(sv.build_spline((i * j + k).astype(np.float64), "cubic-c1"))
    pts = np.array([[1.2, 1.3, 1.4], [2.0, 1.5, 1.1]])
    spline.value_gradient(pts)
    spline.project(pts, 3.0, 4, 1e-9)
    spline.on_surface(pts[[0, 1, 0]][None], 3.0, 0.0, 0.5, 16, 0.15, 0.06, 0.2, 1.5)
    spline.gaps(pts, np.array([[0.0, 0.0, 1.0]] * 2), 3.0, np.array([0.25, 0.5]), 1.0)
