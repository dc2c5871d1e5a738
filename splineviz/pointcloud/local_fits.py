"""Compiled (numba) weighted least-squares fits of the noise-aware projection (thesis §7.2).

One pass over each point's neighbourhood gathers, for every Gaussian width, the weighted
moments ``sum w x^a y^b`` (``a + b <= 2q``) from which the normal matrix of eq. (7.4) is read,
so a degree-3 fit costs 28 sums per neighbour instead of 100 products; the small systems are
solved per point.  NumPy's batched version of the same arithmetic spent most of its time
allocating and filling ``(points, neighbours, monomials)`` temporaries (about 5x slower on
20,000 points).

Conventions as in :mod:`~splineviz.pointcloud.projection`: points ``(N, 3)``, orthonormal
frames ``(N, 3, 3)`` with rows x, y, z, local coordinates in units of the local spacing, the
monomial basis ordered by total degree ``(1, x, y, x^2, xy, y^2, ...)``.
"""

from __future__ import annotations

import numba
import numpy as np

#: highest degree of the smoothing fits (their moments reach degree 2 * MAX_DEGREE)
MAX_DEGREE = 3
_M = (MAX_DEGREE + 1) * (MAX_DEGREE + 2) // 2
_M2 = (2 * MAX_DEGREE + 1) * (2 * MAX_DEGREE + 2) // 2


def _tables():
    """Exponent sums ``(M2,)`` of the degree-6 basis and the ``(M, M)`` positions of the
    products ``b_i b_j`` of the degree-3 basis in it (prefixes serve lower degrees)."""
    e = np.array([(t - b, b) for t in range(2 * MAX_DEGREE + 1) for b in range(t + 1)])
    s = e[:_M, None, :] + e[None, :_M, :]
    t = s.sum(axis=-1)
    return e.sum(axis=1).astype(np.float64), (t * (t + 1) // 2 + s[..., 1]).astype(np.int64)


_EXPONENT_SUM, _PAIR = _tables()


@numba.njit(cache=True)
def _cond(a):
    """Condition number of a symmetric positive semi-definite matrix (inf if singular)."""
    ev = np.linalg.eigvalsh(a)
    return ev[-1] / ev[0] if ev[0] > 0 else np.inf


@numba.njit(cache=True)
def _fits(points, index, valid, frames, scale, ids, widths, degrees, cond_max, with_noise,
          exponent_sum, pair):
    n_scales, n_ids, n_nb = len(widths), len(ids), index.shape[1]
    coeffs = np.zeros((n_scales, n_ids, _M))
    degree = np.zeros((n_scales, n_ids), dtype=np.int64)
    cond = np.zeros((n_scales, n_ids))
    spread = np.zeros((n_scales, n_ids))
    sigma = np.zeros(n_ids)
    mono = np.empty((n_nb, _M2))
    zs = np.empty(n_nb)
    d2 = np.empty(n_nb)
    px = np.empty(2 * MAX_DEGREE + 1)
    py = np.empty(2 * MAX_DEGREE + 1)
    for p in range(n_ids):
        i = ids[p]
        inv = 1.0 / scale[i]
        for k in range(n_nb):
            j = index[i, k]
            rx = points[j, 0] - points[i, 0]
            ry = points[j, 1] - points[i, 1]
            rz = points[j, 2] - points[i, 2]
            x = (frames[i, 0, 0] * rx + frames[i, 0, 1] * ry + frames[i, 0, 2] * rz) * inv
            y = (frames[i, 1, 0] * rx + frames[i, 1, 1] * ry + frames[i, 1, 2] * rz) * inv
            z = (frames[i, 2, 0] * rx + frames[i, 2, 1] * ry + frames[i, 2, 2] * rz) * inv
            zs[k] = z
            d2[k] = x * x + y * y + z * z
            px[0] = 1.0
            py[0] = 1.0
            for e in range(1, 2 * MAX_DEGREE + 1):
                px[e] = px[e - 1] * x
                py[e] = py[e - 1] * y
            c = 0
            for t in range(2 * MAX_DEGREE + 1):
                for b in range(t + 1):
                    mono[k, c] = px[t - b] * py[b]
                    c += 1
        for s in range(n_scales):
            h = widths[s]
            q = degrees[s]
            m = (q + 1) * (q + 2) // 2
            m2 = (2 * q + 1) * (2 * q + 2) // 2
            mom = np.zeros(m2)
            mom2 = np.zeros(m2)
            rz = np.zeros(m)
            sw = 0.0
            for k in range(n_nb):
                if not valid[i, k]:
                    continue
                w = np.exp(-d2[k] / (h * h))
                sw += w
                for c in range(m2):
                    mom[c] += w * mono[k, c]
                for c in range(m):
                    rz[c] += w * zs[k] * mono[k, c]
                if with_noise:
                    for c in range(m2):
                        mom2[c] += w * w * mono[k, c]
            # the fit runs in coordinates divided by h: (x/h)^a (y/h)^b, so that the
            # condition number means the same at every width
            f = h ** -exponent_sum[:m2]
            a = np.empty((m, m))
            for r in range(m):
                for c in range(m):
                    a[r, c] = mom[pair[r, c]] * f[pair[r, c]]
            cnd = _cond(a)
            if not cnd <= cond_max:
                # points near a curve of degree q (Fig. 7.7, scan lines): the plane only
                m = 3
                a = a[:3, :3].copy()
                cnd = _cond(a)
            rhs = np.zeros((m, 2))
            for c in range(m):
                rhs[c, 0] = rz[c] * f[c]
                a[c, c] += 1e-12  # guards exactly singular plane fits (points on a line)
            rhs[0, 1] = 1.0
            sol = np.linalg.solve(a, rhs)
            degree[s, p] = q if m > 3 or q == 1 else 1
            cond[s, p] = cnd
            for c in range(m):
                coeffs[s, p, c] = sol[c, 0] * f[c]  # back to spacing units
            # the value at the origin is sum_k l_k z_k with l_k = w_k b_k . A^-1 e_0
            acc = 0.0
            rss = 0.0
            for k in range(n_nb):
                if not valid[i, k]:
                    continue
                w = np.exp(-d2[k] / (h * h))
                bl = 0.0
                bz = 0.0
                for c in range(m):
                    bl += mono[k, c] * sol[c, 1] * f[c]
                    bz += mono[k, c] * coeffs[s, p, c]
                acc += (w * bl) ** 2
                rss += w * (zs[k] - bz) ** 2
            spread[s, p] = acc
            if with_noise and s == 0:
                # E[sum w r^2] = sigma^2 (sum w - tr(A^-1 B^T W^2 B)) for weighted LS
                c2 = np.empty((m, m))
                for r in range(m):
                    for c in range(m):
                        c2[r, c] = mom2[pair[r, c]] * f[pair[r, c]]
                dof = sw - np.trace(np.linalg.solve(a, c2))
                sigma[p] = np.sqrt(rss / max(dof, 1e-12))
    return coeffs, degree, cond, spread, sigma


def smoothing_fits(points, index, valid, frames, scale, ids, scales, cond_max,
                   noise=False):
    """Weighted least-squares polynomials at several Gaussian widths per point.

    Each fit runs in coordinates divided by its width ``h``; where the condition number of
    its normal matrix exceeds ``cond_max`` (points near a curve of that degree, Fig. 7.7,
    e.g. scan lines) the plane (degree 1) is fitted instead.

    Parameters
    ----------
    points : (N, 3) float64
    index : (N, K) int, neighbour ids per point (column 0 the point itself)
    valid : (N, K) bool, False for neighbours left out (other sheets, padding)
    frames : (N, 3, 3) orthonormal rows x, y, z per point
    scale : (N,) local spacing
    ids : (P,) int, the points to fit
    scales : sequence of (width h in spacings, degree q <= MAX_DEGREE)
    cond_max : float
    noise : bool
        Also estimate the noise from the residuals of the first fit.

    Returns
    -------
    coeffs : (S, P, 10) coefficients in spacing units, zero-padded beyond the degree
    degree : (S, P) int, ``q`` or 1
    cond : (S, P) condition number of the scaled normal matrix
    spread : (S, P) sum of the squared equivalent-kernel weights of the value at the
        origin: its variance is ``spread`` times the noise variance
    sigma : (P,) unbiased residual standard deviation of the first fit, in spacings (zero
        without ``noise``)
    """
    widths = np.array([w for w, _ in scales], dtype=np.float64)
    degrees = np.array([q for _, q in scales], dtype=np.int64)
    return _fits(np.ascontiguousarray(points, dtype=np.float64),
                 np.ascontiguousarray(index, dtype=np.int64),
                 np.ascontiguousarray(valid, dtype=np.bool_),
                 np.ascontiguousarray(frames, dtype=np.float64),
                 np.ascontiguousarray(scale, dtype=np.float64),
                 np.ascontiguousarray(ids, dtype=np.int64), widths, degrees,
                 float(cond_max), bool(noise), _EXPONENT_SUM, _PAIR)
