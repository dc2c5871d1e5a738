"""Compiled (numba) weighted least-squares fits of the noise-aware projection (thesis §7.2).

One pass over each point's neighbourhood gathers, for every Gaussian width, the weighted
moments ``sum w x^a y^b`` (``a + b <= 2q``) from which the normal matrix of eq. (7.4) is read,
so a degree-3 fit costs 28 sums per neighbour instead of 100 products; the small systems are
solved per point. The fits are compiled rather than batched in NumPy because a batched version
spends its time allocating and filling ``(points, neighbours, monomials)`` temporaries.

Conventions as in :mod:`~splineviz.pointcloud.projection`: points ``(N, 3)``, orthonormal
frames ``(N, 3, 3)`` with rows x, y, z, local coordinates in units of the local spacing, the
monomial basis ordered by total degree ``(1, x, y, x^2, xy, y^2, ...)``.  Neighbour id
arrays (``index``, ``sets``) are read as int32: at 80 neighbours an int64 index takes 640 bytes a
point, most of a 2-million-point cloud's memory (clouds of 2^31 points or more would not fit
in memory anyway).
"""

from __future__ import annotations

import numba
import numpy as np

from splineviz.pointcloud.threads import use_allowed_cores

#: highest degree of the smoothing fits (their moments reach degree 2 * MAX_DEGREE)
MAX_DEGREE = 4
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

#: points per chunk of the parallel loops: batches of fewer than two chunks (the front's 64
#: apexes) run on the calling thread without entering a parallel region, whose start costs
#: more than such a batch (Lucy's front: +30 % time)
CHUNK = 512


@numba.njit(cache=True)
def _chunks(n):
    """Number of chunks of about ``CHUNK`` points for ``n`` points (at least 1)."""
    return max(1, n // CHUNK)


@numba.njit(cache=True)
def _cholesky(a, m, low):
    """In-place Cholesky factor of the leading ``m x m`` block of ``a`` (lower triangle).

    Returns the ratio of the largest diagonal entry to the smallest pivot, a cheap lower bound
    of the condition number (each pivot lies between the extreme eigenvalues), or inf when a
    pivot is not positive.  ``low`` is the row from which the factorisation continues.
    """
    big = 0.0
    for r in range(m):
        big = max(big, a[r, r])
    small = np.inf
    for r in range(low, m):
        for c in range(r + 1):
            v = a[r, c]
            for t in range(c):
                v -= a[r, t] * a[c, t]
            if r == c:
                if v <= 0.0:
                    return np.inf
                small = min(small, v)
                a[r, r] = np.sqrt(v)
            else:
                a[r, c] = v / a[c, c]
    for r in range(low):
        small = min(small, a[r, r] ** 2)
    return big / small


@numba.njit(cache=True)
def _solve_factored(a, m, x):
    """Solve ``L L^T y = x`` in place for the factor of :func:`_cholesky`."""
    for r in range(m):
        v = x[r]
        for t in range(r):
            v -= a[r, t] * x[t]
        x[r] = v / a[r, r]
    for r in range(m - 1, -1, -1):
        v = x[r]
        for t in range(r + 1, m):
            v -= a[t, r] * x[t]
        x[r] = v / a[r, r]


@numba.njit(cache=True)
def _lower_inverse(a, m, out):
    """``out[:m, :m]`` = the inverse of the factor ``L`` of :func:`_cholesky` (lower
    triangular; the upper triangle of ``out`` is left as it was)."""
    for i in range(m):
        out[i, i] = 1.0 / a[i, i]
        for j in range(i):
            v = 0.0
            for k in range(j, i):
                v += a[i, k] * out[k, j]
            out[i, j] = -v / a[i, i]


@numba.njit(cache=True, inline="always")
def _local(points, frames, i, j, inv):
    """Coordinates of point j in point i's local frame (rows of frames[i]: two tangents and
    the normal), divided by the scale (``inv`` = 1 / scale[i])."""
    rx = points[j, 0] - points[i, 0]
    ry = points[j, 1] - points[i, 1]
    rz = points[j, 2] - points[i, 2]
    return ((frames[i, 0, 0] * rx + frames[i, 0, 1] * ry + frames[i, 0, 2] * rz) * inv,
            (frames[i, 1, 0] * rx + frames[i, 1, 1] * ry + frames[i, 1, 2] * rz) * inv,
            (frames[i, 2, 0] * rx + frames[i, 2, 1] * ry + frames[i, 2, 2] * rz) * inv)


@numba.njit(cache=True, parallel=True)
def _fits(points, index, valid, frames, scale, ids, widths, degrees, cond_max, with_noise,
          exponent_sum, pair):
    n_scales, n_ids = len(widths), len(ids)
    coeffs = np.zeros((n_scales, n_ids, _M))
    degree = np.zeros((n_scales, n_ids), dtype=np.int64)
    cond = np.zeros((n_scales, n_ids))
    spread = np.zeros((n_scales, n_ids))
    balance = np.zeros((n_scales, n_ids))
    rss = np.zeros((n_scales, n_ids))
    dof = np.zeros((n_scales, n_ids))
    n_chunks = _chunks(n_ids)
    if n_chunks == 1:
        _fits_range(0, n_ids, points, index, valid, frames, scale, ids, widths, degrees,
                    cond_max, with_noise, exponent_sum, pair, coeffs, degree, cond, spread,
                    balance, rss, dof)
        return coeffs, degree, cond, spread, balance, rss, dof
    for c in numba.prange(n_chunks):
        _fits_range(c * n_ids // n_chunks, (c + 1) * n_ids // n_chunks, points, index, valid,
                    frames, scale, ids, widths, degrees, cond_max, with_noise, exponent_sum,
                    pair, coeffs, degree, cond, spread, balance, rss, dof)
    return coeffs, degree, cond, spread, balance, rss, dof


@numba.njit(cache=True)
def _fits_range(lo, hi, points, index, valid, frames, scale, ids, widths, degrees, cond_max,
                with_noise, exponent_sum, pair, coeffs, degree, cond, spread, balance, rss_out,
                dof_out):
    """The fits of points ``ids[lo:hi]`` into the outputs of :func:`_fits`."""
    n_scales, n_nb = len(widths), index.shape[1]
    # the monomials up to the highest degree the moments of these fits need, 2 * max(q)
    top = 2 * max(degrees)
    n_mono = (top + 1) * (top + 2) // 2
    mono = np.empty((n_nb, n_mono))
    zs = np.empty(n_nb)
    wt = np.empty((n_scales, n_nb))
    px = np.empty(top + 1)
    py = np.empty(top + 1)
    a = np.empty((_M, _M))
    c2 = np.empty((_M, _M))
    linv = np.empty((_M, _M))
    x0 = np.empty(_M)
    e0 = np.empty(_M)
    mom = np.empty(n_mono)
    mom2 = np.empty(n_mono)
    rhs = np.empty(_M)
    # the fit runs in coordinates divided by h: (x/h)^a (y/h)^b, so that the condition
    # number means the same at every width; these are the factors per moment and width
    unscale = np.empty((n_scales, n_mono))
    for s in range(n_scales):
        for c in range(n_mono):
            unscale[s, c] = widths[s] ** -exponent_sum[c]
    for p in range(lo, hi):
        i = ids[p]
        inv = 1.0 / scale[i]
        for k in range(n_nb):
            j = index[i, k]
            x, y, z = _local(points, frames, i, j, inv)
            zs[k] = z
            d2 = x * x + y * y + z * z
            for s in range(n_scales):
                wt[s, k] = np.exp(-d2 / (widths[s] * widths[s])) if valid[i, k] else 0.0
            px[0] = 1.0
            py[0] = 1.0
            for e in range(1, top + 1):
                px[e] = px[e - 1] * x
                py[e] = py[e - 1] * y
            c = 0
            for t in range(top + 1):
                for b in range(t + 1):
                    mono[k, c] = px[t - b] * py[b]
                    c += 1
        for s in range(n_scales):
            h = widths[s]
            q = degrees[s]
            m = (q + 1) * (q + 2) // 2
            m2 = (2 * q + 1) * (2 * q + 2) // 2
            mom[:m2] = 0.0
            mom2[:m2] = 0.0
            rhs[:m] = 0.0
            sw = 0.0
            for k in range(n_nb):
                w = wt[s, k]
                if w == 0.0:
                    continue
                sw += w
                if with_noise:
                    w2 = w * w
                    for c in range(m2):
                        mom[c] += w * mono[k, c]
                        mom2[c] += w2 * mono[k, c]
                else:
                    for c in range(m2):
                        mom[c] += w * mono[k, c]
                wz = w * zs[k]
                for c in range(m):
                    rhs[c] += wz * mono[k, c]
            f = unscale[s]
            # weighted centroid of the neighbourhood in the tangent plane, in widths
            balance[s, p] = np.hypot(mom[1], mom[2]) / (h * max(mom[0], 1e-300))
            for r in range(m):
                for c in range(m):
                    a[r, c] = mom[pair[r, c]] * f[pair[r, c]]
                a[r, r] += 1e-12  # guards exactly singular plane fits (points on a line)
            cnd = _cholesky(a, m, 0)
            if not cnd <= cond_max:
                # points near a curve of degree q (Fig. 7.7, scan lines): the plane only;
                # the leading 3 x 3 block is factored again from the moments
                m = 3
                for r in range(3):
                    for c in range(3):
                        a[r, c] = mom[pair[r, c]] * f[pair[r, c]]
                    a[r, r] += 1e-12
                cnd = _cholesky(a, m, 0)
            degree[s, p] = q if m > 3 or q == 1 else 1
            cond[s, p] = cnd
            for c in range(m):
                x0[c] = rhs[c] * f[c]
                e0[c] = 0.0
            e0[0] = 1.0
            _solve_factored(a, m, x0)
            _solve_factored(a, m, e0)
            for c in range(m):
                coeffs[s, p, c] = x0[c] * f[c]  # back to spacing units
                e0[c] *= f[c]
            # the value at the origin is sum_k l_k z_k with l_k = w_k b_k . A^-1 e_0
            acc = 0.0
            rss = 0.0
            for k in range(n_nb):
                w = wt[s, k]
                if w == 0.0:
                    continue
                bl = 0.0
                bz = 0.0
                for c in range(m):
                    bl += mono[k, c] * e0[c]
                    bz += mono[k, c] * coeffs[s, p, c]
                acc += (w * bl) ** 2
                rss += w * (zs[k] - bz) ** 2
            spread[s, p] = acc
            if with_noise:
                # E[sum w r^2] = sigma^2 (sum w - tr(A^-1 B^T W^2 B)) for weighted LS; with
                # A = L L^T the trace is sum_i l_i^T C l_i over the rows l_i of L^-1, which
                # costs one triangular inverse instead of m solves
                for r in range(m):
                    for c in range(m):
                        c2[r, c] = mom2[pair[r, c]] * f[pair[r, c]]
                _lower_inverse(a, m, linv)
                tr = 0.0
                for i in range(m):
                    for r in range(i + 1):
                        v = 0.0
                        for c in range(i + 1):
                            v += c2[r, c] * linv[i, c]
                        tr += linv[i, r] * v
                rss_out[s, p] = rss
                dof_out[s, p] = max(sw - tr, 1e-12)


def smoothing_fits(points, index, valid, frames, scale, ids, scales, cond_max,
                   noise=False):
    """Weighted least-squares polynomials at several Gaussian widths per point.

    Each fit runs in coordinates divided by its width ``h``; where the condition of its
    normal matrix (estimated from its Cholesky pivots) exceeds ``cond_max`` (points near a
    curve of that degree, Fig. 7.7, e.g. scan lines) the plane (degree 1) is fitted instead.

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
        Also return the residuals of every fit and the noise they measure.

    Returns
    -------
    coeffs : (S, P, 15) coefficients in spacing units, zero-padded beyond the degree
    degree : (S, P) int, ``q`` or 1
    cond : (S, P) largest diagonal entry over smallest Cholesky pivot of the scaled normal
        matrix (a lower bound of its condition number)
    spread : (S, P) sum of the squared equivalent-kernel weights of the value at the
        origin: its variance is ``spread`` times the noise variance
    balance : (S, P) distance of the weighted centroid of the neighbourhood from the point,
        in the tangent plane and in units of the width: about 0.56 at a straight border of
        the cloud (half a Gaussian), near 0 inside
    sigma : (P,) unbiased residual standard deviation of the first fit, in spacings (zero
        without ``noise``)
    rss : (S, P) weighted residual sum of squares ``sum w r^2`` of each fit (spacings^2;
        zero without ``noise``)
    dof : (S, P) its expectation over the noise variance, ``sum w - tr(A^-1 B^T W^2 B)``
        (zero without ``noise``)
    """
    widths = np.array([w for w, _ in scales], dtype=np.float64)
    degrees = np.array([q for _, q in scales], dtype=np.int64)
    use_allowed_cores()
    out = _fits(np.ascontiguousarray(points, dtype=np.float64),
                np.ascontiguousarray(index, dtype=np.int32),
                np.ascontiguousarray(valid, dtype=np.bool_),
                np.ascontiguousarray(frames, dtype=np.float64),
                np.ascontiguousarray(scale, dtype=np.float64),
                np.ascontiguousarray(ids, dtype=np.int64), widths, degrees,
                float(cond_max), bool(noise), _EXPONENT_SUM, _PAIR)
    rss, dof = out[5], out[6]
    sigma = np.sqrt(rss[0] / dof[0]) if noise else np.zeros(len(ids))
    return (*out[:5], sigma, rss, dof)


@numba.njit(cache=True, parallel=True)
def _sheet_mask(normals, index, cos_min):
    n, k = index.shape
    out = np.empty((n, k), dtype=np.bool_)
    for i in numba.prange(n):
        out[i, 0] = True
        for c in range(1, k):
            j = index[i, c]
            out[i, c] = (normals[j, 0] * normals[i, 0] + normals[j, 1] * normals[i, 1]
                         + normals[j, 2] * normals[i, 2]) > cos_min
    return out


def sheet_mask(normals, index, cos_min):
    """Neighbours on the point's own sheet: ``(N, K)`` bool, True where the oriented normals
    of neighbour ``index[i, c]`` and point ``i`` have a dot product above ``cos_min`` (column 0,
    the point itself, always).

    Parameters
    ----------
    normals : (N, 3) unit normals, consistently oriented
    index : (N, K) int neighbour ids
    cos_min : float
    """
    use_allowed_cores()
    return _sheet_mask(np.ascontiguousarray(normals, dtype=np.float64),
                       np.ascontiguousarray(index, dtype=np.int32), float(cos_min))


@numba.njit(cache=True, parallel=True)
def _neighbour_median(values, index):
    n, k = index.shape
    out = np.empty(n)
    for i in numba.prange(n):
        row = np.empty(k)
        for c in range(k):
            row[c] = values[index[i, c]]
        out[i] = np.median(row)
    return out


def neighbour_median(values, index):
    """``np.median(values[index], axis=1)``: the median over each point's neighbours.

    Parameters
    ----------
    values : (N,) float64
    index : (M, K) int neighbour ids

    Returns
    -------
    (M,) float64
    """
    use_allowed_cores()
    return _neighbour_median(np.ascontiguousarray(values, dtype=np.float64),
                             np.ascontiguousarray(index, dtype=np.int32))


@numba.njit(cache=True, parallel=True)
def _nearest_in_rows(indptr, indices, data, k):
    n = len(indptr) - 1
    out = np.empty((n, k), dtype=np.int32)
    for i in numba.prange(n):
        lo, hi = indptr[i], indptr[i + 1]
        # stable: equal lengths keep the order of the row, as np.lexsort
        order = np.argsort(data[lo:hi], kind="mergesort")
        out[i, :] = i
        for c in range(min(k - 1, hi - lo)):
            out[i, 1 + c] = indices[lo + order[c]]
    return out


def nearest_in_rows(graph, k):
    """Each row's id followed by its ``k - 1`` nearest graph neighbours (smallest stored
    lengths, ties in stored order); rows with fewer neighbours are padded with their own id.

    Parameters
    ----------
    graph : (N, N) scipy.sparse.csr_matrix of edge lengths
    k : int

    Returns
    -------
    (N, k) int32
    """
    use_allowed_cores()
    return _nearest_in_rows(np.ascontiguousarray(graph.indptr, dtype=np.int64),
                            np.ascontiguousarray(graph.indices, dtype=np.int64),
                            np.ascontiguousarray(graph.data, dtype=np.float64), int(k))


def moment_pairs(q: int) -> np.ndarray:
    """Positions ``(m, m)`` of the products ``b_i b_j`` of the degree-``q`` basis in the list of
    monomials of degree ``2 q`` (both ordered by total degree), ``m = (q + 1)(q + 2) / 2``."""
    e = np.array([(t - b, b) for t in range(q + 1) for b in range(t + 1)])
    s = e[:, None, :] + e[None, :, :]
    t = s.sum(axis=-1)
    return (t * (t + 1) // 2 + s[..., 1]).astype(np.int64)


@numba.njit(cache=True)
def _condition_ok(a, m, cond_max, f, g):
    """Whether the 2-norm condition number of the SPD block ``a[:m, :m]`` is at most
    ``cond_max``, and the Cholesky factor of the block in ``f`` (lower triangle).

    The same decision as from the extreme eigenvalues, at a fraction of their cost: for a
    shift ``s``, ``s I - A`` is positive definite exactly when ``s > lambda_max`` and
    ``A - (s / cond_max) I`` exactly when ``lambda_min > s / cond_max``.  Both at once prove
    ``cond <= cond_max``, neither proves ``cond >= cond_max``, and one alone tells on which
    side of ``lambda_max`` the shift lies: ``s`` is bisected (geometrically) between bounds of
    ``lambda_max`` until one of the two proofs holds, a few Cholesky factorisations (1 us at
    degree 5, an eigenvalue solve 16 us) except within a hair of ``cond_max``, where the
    eigenvalues decide.

    Parameters
    ----------
    a : (M, M) float, the block in its leading ``m x m`` part
    m : int
    cond_max : float
    f, g : (M, M) float work arrays; ``f`` receives the factor

    Returns
    -------
    ok : bool
    cond : float, a lower bound of the condition number (largest diagonal entry over the
        smallest pivot; inf when the block is not positive definite).
    """
    for r in range(m):
        for c in range(r + 1):
            f[r, c] = a[r, c]
    lb = _cholesky(f, m, 0)
    if not lb <= cond_max:
        return False, lb
    # lambda_max lies between the Rayleigh quotient of the square roots of the diagonal
    # (at least the largest diagonal entry) and the row-sum and Frobenius bounds
    gers = 0.0
    fro = 0.0
    num = 0.0
    den = 0.0
    big = 0.0
    for r in range(m):
        row = 0.0
        acc = 0.0
        for c in range(m):
            row += abs(a[r, c])
            fro += a[r, c] * a[r, c]
            acc += a[r, c] * np.sqrt(a[c, c])
        gers = max(gers, row)
        num += acc * np.sqrt(a[r, r])
        den += a[r, r]
        big = max(big, a[r, r])
    lo = max(big, num / den)
    hi = min(gers, np.sqrt(fro))
    for _ in range(60):
        s = np.sqrt(lo * hi)
        for r in range(m):
            for c in range(r + 1):
                g[r, c] = -a[r, c]
            g[r, r] += s
        above = _cholesky(g, m, 0) < np.inf  # s > lambda_max
        for r in range(m):
            for c in range(r + 1):
                g[r, c] = a[r, c]
            g[r, r] -= s / cond_max
        inside = _cholesky(g, m, 0) < np.inf  # lambda_min > s / cond_max
        if above and inside:
            return True, lb
        if not above and not inside:
            return False, lb
        if above:
            hi = s
        else:
            lo = s
        if hi <= lo * (1.0 + 1e-12):
            break
    ev = np.linalg.eigvalsh(np.ascontiguousarray(a[:m, :m]))
    return ev[0] > 0.0 and ev[m - 1] <= cond_max * ev[0], lb


@numba.njit(cache=True, parallel=True)
def _variable_fits(points, index, valid, frames, scale, ids, n_nb, q_max, cond_max, pair):
    m_max = (q_max + 1) * (q_max + 2) // 2
    n_ids = len(ids)
    coeffs = np.zeros((n_ids, m_max))
    degree = np.ones(n_ids, dtype=np.int64)
    cond = np.zeros(n_ids)
    n_chunks = _chunks(n_ids)
    if n_chunks == 1:
        _variable_range(0, n_ids, points, index, valid, frames, scale, ids, n_nb, q_max,
                        cond_max, pair, coeffs, degree, cond)
        return coeffs, degree, cond
    for c in numba.prange(n_chunks):
        _variable_range(c * n_ids // n_chunks, (c + 1) * n_ids // n_chunks, points, index,
                        valid, frames, scale, ids, n_nb, q_max, cond_max, pair, coeffs,
                        degree, cond)
    return coeffs, degree, cond


@numba.njit(cache=True)
def _variable_range(lo, hi, points, index, valid, frames, scale, ids, n_nb, q_max, cond_max,
                    pair, coeffs, degree, cond):
    """The fits of points ``ids[lo:hi]`` into the outputs of :func:`_variable_fits`."""
    m_max = (q_max + 1) * (q_max + 2) // 2
    m2 = (2 * q_max + 1) * (2 * q_max + 2) // 2
    mom = np.empty(m2)
    rhs = np.empty(m_max)
    px = np.empty(2 * q_max + 1)
    py = np.empty(2 * q_max + 1)
    a = np.empty((m_max, m_max))
    f = np.empty((m_max, m_max))
    g = np.empty((m_max, m_max))
    v = np.empty(m_max)
    for p in range(lo, hi):
        i = ids[p]
        inv = 1.0 / scale[i]
        mom[:] = 0.0
        rhs[:] = 0.0
        for k in range(n_nb):
            if not valid[i, k]:
                continue
            j = index[i, k]
            x, y, z = _local(points, frames, i, j, inv)
            w = np.exp(-(x * x + y * y + z * z))  # eq. (7.2), h = one spacing
            px[0] = w
            py[0] = 1.0
            for e in range(1, 2 * q_max + 1):
                px[e] = px[e - 1] * x
                py[e] = py[e - 1] * y
            c = 0
            for t in range(2 * q_max + 1):
                for b in range(t + 1):
                    val = px[t - b] * py[b]
                    mom[c] += val
                    if c < m_max:
                        rhs[c] += val * z
                    c += 1
        q = q_max
        while True:
            m = (q + 1) * (q + 2) // 2
            for r in range(m):
                for c in range(m):
                    a[r, c] = mom[pair[r, c]]
                a[r, r] += 1e-12  # guards exactly singular plane fits (points on a line)
            ok, cnd = _condition_ok(a, m, cond_max, f, g)
            if ok or q == 1:
                break
            q -= 1
        degree[p] = q
        cond[p] = cnd
        if not cnd < np.inf:
            # the plane of points on a line: the factor of a matrix regularised a little more
            big = 0.0
            for r in range(3):
                big = max(big, a[r, r])
            for r in range(3):
                for c in range(3):
                    f[r, c] = a[r, c]
                f[r, r] += 1e-9 * big
            if not _cholesky(f, 3, 0) < np.inf:
                continue  # no neighbours at all: the plane z = 0 through the point
        for c in range(m):
            v[c] = rhs[c]
        _solve_factored(f, m, v)
        for c in range(m):
            coeffs[p, c] = v[c]


def variable_degree_fits(points, index, valid, frames, scale, ids, n_neighbours, q_max,
                         cond_max):
    """Interpolating local polynomials of the highest well-conditioned degree (thesis §7.2).

    Per point: the weighted least-squares polynomial of eq. (7.1) over its first
    ``n_neighbours`` neighbours, weights ``exp(-|x|^2)`` in local coordinates of unit spacing
    (eq. 7.2), the degree lowered from ``q_max`` while the 2-norm condition number of the
    normal matrix (eq. 7.4) exceeds ``cond_max`` (Fig. 7.7); degree 1 is always taken.  The
    same choice as :func:`~splineviz.pointcloud.projection.fit_polynomials`, with the normal
    matrices read from the moments ``sum w x^a y^b`` (``a + b <= 2 q_max``) of one pass over
    the neighbourhood and the condition decided by shifted Cholesky factorisations
    (:func:`_condition_ok`).

    Parameters
    ----------
    points : (N, 3) float64
    index : (N, K) int, neighbour ids per point, nearest first (column 0 the point itself)
    valid : (N, K) bool, False for neighbours left out (other sheets)
    frames : (N, 3, 3) orthonormal rows x, y, z per point
    scale : (N,) local spacing
    ids : (P,) int, the points to fit
    n_neighbours : int, columns of ``index`` used (at most K)
    q_max : int, highest degree (1 ... 6)
    cond_max : float

    Returns
    -------
    coeffs : (P, m) coefficients in spacing units for the degree-``q_max`` basis
        (``m = (q_max + 1)(q_max + 2) / 2``), zero beyond each chosen degree
    degree : (P,) int
    cond : (P,) a lower bound of the chosen normal matrix's condition number (largest
        diagonal entry over the smallest Cholesky pivot)
    """
    q_max = int(q_max)
    use_allowed_cores()
    return _variable_fits(np.ascontiguousarray(points, dtype=np.float64),
                          np.ascontiguousarray(index, dtype=np.int32),
                          np.ascontiguousarray(valid, dtype=np.bool_),
                          np.ascontiguousarray(frames, dtype=np.float64),
                          np.ascontiguousarray(scale, dtype=np.float64),
                          np.ascontiguousarray(ids, dtype=np.int64),
                          min(int(n_neighbours), index.shape[1]), q_max, float(cond_max),
                          moment_pairs(q_max))


@numba.njit(cache=True)
def _evaluate(c, q, u, v, pu, pv):
    """Value and first derivatives at ``(u, v)`` of the polynomial ``c`` of degree ``q``."""
    pu[0] = 1.0
    pv[0] = 1.0
    for e in range(1, q + 1):
        pu[e] = pu[e - 1] * u
        pv[e] = pv[e - 1] * v
    z = 0.0
    zu = 0.0
    zv = 0.0
    idx = 0
    for t in range(q + 1):
        for b in range(t + 1):
            a = t - b
            z += c[idx] * pu[a] * pv[b]
            if a > 0:
                zu += c[idx] * a * pu[a - 1] * pv[b]
            if b > 0:
                zv += c[idx] * b * pu[a] * pv[b - 1]
            idx += 1
    return z, zu, zv


@numba.njit(cache=True)
def _project_one(points, frames, scale, coeffs, degree, reach, i, x, iterations, pu, pv, loc,
                 pos, nrm):
    """Project ``x (3,)`` onto the polynomial of point ``i``: foot into ``pos (3,)``, unit
    normal into ``nrm (3,)`` (see :func:`project_on_polynomials`)."""
    s = scale[i]
    for a in range(3):
        loc[a] = (frames[i, a, 0] * (x[0] - points[i, 0])
                  + frames[i, a, 1] * (x[1] - points[i, 1])
                  + frames[i, a, 2] * (x[2] - points[i, 2])) / s
    u, v = loc[0], loc[1]
    rad = np.hypot(u, v)
    if rad > reach[i]:
        u *= reach[i] / rad
        v *= reach[i] / rad
    q = degree[i]
    for _ in range(iterations):
        z, zu, zv = _evaluate(coeffs[i], q, u, v, pu, pv)
        # J = [[1, 0], [0, 1], [zu, zv]];  solve (J^T J) d = J^T res
        g0 = (loc[0] - u) + zu * (loc[2] - z)
        g1 = (loc[1] - v) + zv * (loc[2] - z)
        a00, a01, a11 = 1 + zu * zu, zu * zv, 1 + zv * zv
        det = a00 * a11 - a01 * a01
        du = (a11 * g0 - a01 * g1) / det
        dv = (a00 * g1 - a01 * g0) / det
        step = np.hypot(du, dv)
        factor = 1.0 / step if step > 1.0 else 1.0  # at most one spacing per step
        u += du * factor
        v += dv * factor
        # the polynomial is only valid where its points were: keep the foot inside
        rad = np.hypot(u, v)
        if rad > reach[i]:
            u *= reach[i] / rad
            v *= reach[i] / rad
    z, zu, zv = _evaluate(coeffs[i], q, u, v, pu, pv)
    length = np.sqrt(zu * zu + zv * zv + 1.0)
    for a in range(3):
        pos[a] = points[i, a] + s * (frames[i, 0, a] * u + frames[i, 1, a] * v
                                     + frames[i, 2, a] * z)
        nrm[a] = (-frames[i, 0, a] * zu - frames[i, 1, a] * zv + frames[i, 2, a]) / length


@numba.njit(cache=True)
def _median_of(values, k):
    """Median of ``values[:k]``: the middle value, or the mean of the two middle ones for
    even ``k`` (``values`` is sorted in place)."""
    for t in range(1, k):
        v = values[t]
        j = t - 1
        while j >= 0 and values[j] > v:
            values[j + 1] = values[j]
            j -= 1
        values[j + 1] = v
    return values[k // 2] if k % 2 else 0.5 * (values[k // 2 - 1] + values[k // 2])


@numba.njit(cache=True, parallel=True)
def _project_median(points, frames, scale, coeffs, degree, reach, sets, r, iterations):
    m = sets.shape[0]
    pos = np.empty((m, 3))
    nrm = np.empty((m, 3))
    n_chunks = _chunks(m)
    if n_chunks == 1:
        _median_range(0, m, points, frames, scale, coeffs, degree, reach, sets, r, iterations,
                      pos, nrm)
        return pos, nrm
    for c in numba.prange(n_chunks):
        _median_range(c * m // n_chunks, (c + 1) * m // n_chunks, points, frames, scale,
                      coeffs, degree, reach, sets, r, iterations, pos, nrm)
    return pos, nrm


@numba.njit(cache=True)
def _median_range(lo, hi, points, frames, scale, coeffs, degree, reach, sets, r, iterations,
                  pos, nrm):
    """The medians of queries ``lo:hi`` into ``pos`` and ``nrm`` (:func:`_project_median`)."""
    k = sets.shape[1]
    each_pos = np.empty((k, 3))
    each_nrm = np.empty((k, 3))
    column = np.empty(k)
    pu = np.empty(coeffs.shape[1])
    pv = np.empty(coeffs.shape[1])
    loc = np.empty(3)
    for p in range(lo, hi):
        for c in range(k):
            _project_one(points, frames, scale, coeffs, degree, reach, sets[p, c], r[p],
                         iterations, pu, pv, loc, each_pos[c], each_nrm[c])
        for a in range(3):
            for c in range(k):
                column[c] = each_pos[c, a]
            pos[p, a] = _median_of(column, k)
            for c in range(k):
                column[c] = each_nrm[c, a]
            nrm[p, a] = _median_of(column, k)


def project_median(points, frames, scale, coeffs, degree, reach, sets, r, iterations):
    """Component-wise medians of the projections of each query onto several polynomials
    (thesis §7.2): query ``r[p]`` is projected (:func:`project_on_polynomials`) onto the
    polynomials of points ``sets[p]``.

    Parameters
    ----------
    points, frames, scale, coeffs, degree, reach : as for :func:`project_on_polynomials`
    sets : (M, k) int, the polynomials of each query
    r : (M, 3) query points
    iterations : int

    Returns
    -------
    positions (M, 3), normals (M, 3): the medians (the normals not renormalised).
    """
    f64 = np.float64
    use_allowed_cores()
    return _project_median(np.ascontiguousarray(points, f64), np.ascontiguousarray(frames, f64),
                           np.ascontiguousarray(scale, f64), np.ascontiguousarray(coeffs, f64),
                           np.ascontiguousarray(degree, np.int64),
                           np.ascontiguousarray(reach, f64),
                           np.ascontiguousarray(sets, np.int32), np.ascontiguousarray(r, f64),
                           int(iterations))


def project_on_polynomials(points, frames, scale, coeffs, degree, reach, ids, r, iterations):
    """Orthogonal projection of query points onto the local polynomial graphs of points ``ids``.

    Gauss-Newton on the foot parameters, started at the vertical projection; the step is
    damped (one spacing per step) and the foot point kept within ``reach`` of the origin, so
    that far queries cannot diverge.

    Parameters
    ----------
    points : (N, 3) origins of the local frames
    frames : (N, 3, 3) orthonormal rows x, y, z
    scale : (N,) local spacing (unit of the local coordinates)
    coeffs : (N, m) polynomial coefficients, zero-padded beyond ``degree``
    degree : (N,) int
    reach : (N,) largest foot radius in spacings
    ids : (P,) int, the polynomial of each query
    r : (P, 3) query points
    iterations : int

    Returns
    -------
    positions (P, 3), unit normals (P, 3) in world coordinates.
    """
    # the median of one projection is that projection
    return project_median(points, frames, scale, coeffs, degree, reach,
                          np.asarray(ids).reshape(-1, 1), r, iterations)


def compile_kernels() -> None:
    """Compile the kernels into numba's on-disk cache (install.sh runs this once: the first
    compilation takes 10-20 s, a cached load well under one)."""
    from scipy import sparse

    rng = np.random.default_rng(0)
    points = rng.normal(size=(12, 3))
    index = np.argsort(np.linalg.norm(points[:, None] - points[None], axis=-1), axis=1)
    frames = np.broadcast_to(np.eye(3), (12, 3, 3))
    scale = np.ones(12)
    ids = np.arange(12)
    smoothing_fits(points, index, np.ones(index.shape, dtype=bool), frames, scale, ids,
                   ((1.6, 3), (2.6, 2)), 1e4, noise=True)
    variable_degree_fits(points, index, sheet_mask(points, index, -2.0), frames, scale, ids,
                         8, 5, 1e4)
    project_on_polynomials(points, frames, scale, np.zeros((12, 21)), np.full(12, 5),
                           np.full(12, 3.0), ids, points, 3)
    project_median(points, frames, scale, np.zeros((12, 21)), np.full(12, 5), np.full(12, 3.0),
                   index[:, :7], points, 3)
    neighbour_median(scale, index)
    nearest_in_rows(sparse.csr_matrix(np.ones((12, 12))), 7)
