"""Variable-degree local polynomial surfaces and the point projection (thesis §7.2).

Conventions: input points ``(N, 3)`` float64; query points ``(M, 3)``.  Each input point
``p_i`` owns a local coordinate system (LCS): origin ``p_i``, orthonormal rows
``frames[i] = (x_axis, y_axis, z_axis)`` and a scale ``scale[i]`` (the local sample spacing) so
that local coordinates ``frames[i] @ (x - p_i) / scale[i]`` have unit average spacing, which is
where the condition number of the normal equations is a meaningful degree criterion (§7.2).
The local surface is the graph ``z = p_i(x, y)`` of a bivariate polynomial of degree
``degree[i]`` (1 ... ``q_max``) in the monomial basis ordered by total degree
``(1, x, y, x^2, xy, y^2, ...)`` (eq. 7.3), so the basis of a lower degree is a prefix of the
basis of a higher one.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import sparse

from splineviz.core.errors import SplinevizError
from splineviz.pointcloud.cocone import (
    Connectivity,
    cocone_connectivity,
    knn_connectivity,
    nearest_points,
    tree_query,
)
from splineviz.pointcloud.local_fits import (
    nearest_in_rows,
    neighbour_median,
    project_median,
    sheet_mask,
    smoothing_fits,
    variable_degree_fits,
)

#: highest polynomial degree tried (thesis: "around 5")
Q_MAX = 5
#: largest accepted condition number of A (eq. 7.4) after scaling to unit spacing
COND_MAX = 1.0e4
#: neighbours are collected out to this many smoothing lengths h (weight e^-9 ~ 1e-4 there)
CUTOFF = 3.0
#: LCS re-orientation (Fig. 7.5): bisect while the polynomial normal deviates more than this
MAX_TILT = np.deg2rad(10.0)
#: at most this many bisection steps
MAX_BISECTIONS = 6
#: at most this many (closest) points per neighbourhood
MAX_NEIGHBOURS = 96
#: breadth-first search depth limit (levels of the neighbour graph)
MAX_LEVELS = 16
#: number of angular sectors used by the overlap (convex-hull) rule of Fig. 7.6
HULL_SECTORS = 12
#: a point is an overlap when its projected radius is below this fraction of the region
#: already covered in its direction by earlier breadth-first levels
HULL_SHRINK = 0.5
#: polynomials whose projections are combined by the component-wise median
MEDIAN_NEIGHBOURS = 7
#: queries that move farther than this many spacings are projected a second time
FAR_SPACINGS = 2.0
#: nearest input points searched for one whose normal agrees with a normal hint
HINT_CANDIDATES = 8
#: Gauss-Newton iterations of the orthogonal projection onto a polynomial graph
PROJECTION_ITERATIONS = 3
#: nearest points of the variable-degree fit of clean points in the adaptive mode (3 spacings)
CLEAN_NEIGHBOURS = 40
#: adaptive mode: nearest points gathered per neighbourhood (the widest scale's support)
ADAPTIVE_NEIGHBOURS = 80
#: adaptive mode: Gaussian widths h (in local spacings) and polynomial degrees of the smoothing
#: fits, narrowest first; the first one also measures the noise
SCALES = ((1.6, 3), (2.6, 2), (4.2, 2))
#: intersection-of-confidence-intervals rule: half width of an interval in standard deviations
ICI_KAPPA = 2.0
#: adaptive mode: the higher-degree alternative of the widest fit (the degree test of
#: :func:`choose_fit`): at curvature detail too gentle to stop the widening (the bunny's ears,
#: face and rims) the quadratic's bias, not the noise, set the largest errors.  Degree 4 also
#: holds the even (quartic) part of a bend, which biases a quadratic's value at the point; a
#: cubic holds only the odd part (noisy bunny, 99th-percentile error against the clean scan:
#: 0.215 % of the diagonal with a cubic at 4.2 spacings, 0.206 % with this).  Widths 3.0-4.2
#: were measured: 3.4 gave the smallest Hausdorff distances over the benchmark clouds.  Its
#: value varies more than the widest quadratic's (variance factor 0.13 against 0.056), so
#: only the test lets it in
DETAIL_SCALE = (3.4, 4)
#: degree test: the alternative is kept when it lowers the weighted residual sum by more than
#: this many times what it lowers it by on noise alone: the 99th percentile of chi-squared
#: with its 9 more parameters, over 9 (``scipy.stats.chi2.ppf(0.99, 9) / 9``).  Gaussian
#: weights make the ratio's tail heavier: on a noisy sphere, which has no terms past the
#: quadratic, 6-7 % of the points pass (its 99th-percentile error rises by 3-4 %)
DEGREE_TEST = 2.41
#: adaptive mode: points fitted per block (the wider candidates of a block take ~700 bytes a
#: point while it is chosen among them)
FIT_BLOCK = 65536
#: noise below this fraction of the spacing counts as none: the interpolating variable-degree
#: fit of §7.2 is kept (its error on clean data is far below what any smoothing fit reaches)
CLEAN_NOISE = 1e-3
#: the cloud's noise floor: this percentile of the points' measured noise levels (residuals
#: hold the fits' bias as well as the noise, and bias only adds, so the floor shows where the
#: surface is flattest)
NOISE_FLOOR_PERCENTILE = 10.0
#: the noise level used at a point is at most this many times the cloud's noise floor
NOISE_CAP = 2.0
#: a fit whose weighted neighbourhood centroid lies farther than this many widths from the
#: point leans on one side (a border of the cloud: half a Gaussian gives 0.56) and is not used
MAX_BALANCE = 0.35
#: neighbours whose oriented normal deviates more than this from the point's (cos) belong to
#: another sheet of the surface (the two sides of a thin part) and are left out
SHEET_COS = 0.0


class ProjectionError(SplinevizError, ValueError):
    """Invalid parameters for the projection or invalid query points."""


def monomial_exponents(q: int) -> np.ndarray:
    """Exponents ``(a, b)`` of ``x^a y^b`` with ``a + b <= q``, ordered by total degree.

    Returns
    -------
    (m, 2) int with ``m = (q + 1)(q + 2) / 2``; row order ``1, x, y, x^2, xy, y^2, ...``
    (eq. 7.3), so the first ``(k + 1)(k + 2) / 2`` rows are the basis of degree ``k``.
    """
    return np.array([(t - b, b) for t in range(q + 1) for b in range(t + 1)], dtype=int)


def basis_size(q: int) -> int:
    """Dimension ``(q + 1)(q + 2) / 2`` of bivariate polynomials of degree ``q``."""
    return (q + 1) * (q + 2) // 2


def _powers(x: np.ndarray, q: int) -> np.ndarray:
    """``x[..., None] ** arange(q + 1)`` without pow calls; shape ``x.shape + (q + 1,)``."""
    out = np.empty(x.shape + (q + 1,))
    out[..., 0] = 1.0
    for k in range(1, q + 1):
        out[..., k] = out[..., k - 1] * x
    return out


def basis(x: np.ndarray, y: np.ndarray, q: int) -> np.ndarray:
    """Monomial basis ``b(x)`` of eq. (7.3) at points; shape ``x.shape + (m,)``."""
    e = monomial_exponents(q)
    return _powers(x, q)[..., e[:, 0]] * _powers(y, q)[..., e[:, 1]]


def frames_from_normals(normals: np.ndarray) -> np.ndarray:
    """Orthonormal frames with z-axis ``normals``: ``(N, 3)`` -> ``(N, 3, 3)`` (rows x, y, z)."""
    z = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    helper = np.zeros_like(z)
    helper[np.arange(len(z)), np.argmin(np.abs(z), axis=1)] = 1.0
    x = np.cross(helper, z)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


@dataclass(frozen=True, eq=False)
class Neighbourhoods:
    """Padded neighbourhoods: ``index (N, K)`` point ids, ``level (N, K)`` breadth-first level
    (0 for the point itself), ``valid (N, K)`` bool."""

    index: np.ndarray
    level: np.ndarray
    valid: np.ndarray


def collect_neighbourhoods(points: np.ndarray, graph: sparse.csr_matrix,
                           radius: np.ndarray) -> Neighbourhoods:
    """Breadth-first search over the neighbour graph with the r_c rule (§7.2).

    ``p_j`` is collected for ``p_i`` when a graph path from ``p_i`` to ``p_j`` exists on which
    no point is farther than ``r_c = radius[i]`` from ``p_i``: each level expands the previous
    level by one graph step and drops the points outside the ball, so paths that leave the ball
    (to another sheet of the surface, Fig. 7.3 right) are cut.  All rows are expanded at once
    with sparse matrix products.

    Parameters
    ----------
    points : (N, 3)
    graph : (N, N) symmetric sparse neighbour graph
    radius : (N,) r_c per point

    Returns
    -------
    Neighbourhoods
    """
    n = len(points)
    adj = graph.copy().tocsr()
    adj.data = np.ones_like(adj.data)
    eye = sparse.identity(n, format="csr")
    reached = eye.copy()
    level_of = eye.copy()  # value = level + 1
    frontier = eye
    for level in range(1, MAX_LEVELS + 1):
        step = (frontier @ adj).tocoo()
        d = np.linalg.norm(points[step.row] - points[step.col], axis=1)
        keep = d <= radius[step.row]
        step = sparse.csr_matrix((np.ones(keep.sum()), (step.row[keep], step.col[keep])),
                                 shape=(n, n))
        step.data[:] = 1.0
        new = step - step.multiply(reached)
        new.eliminate_zeros()
        if new.nnz == 0:
            break
        new.data[:] = 1.0
        reached = reached + new
        level_of = level_of + new * (level + 1)
        frontier = new
    level_of = level_of.tocoo()
    rows, ids, lev = level_of.row, level_of.col, np.rint(level_of.data).astype(int) - 1
    # keep the MAX_NEIGHBOURS closest of each row (clouds of very uneven density would
    # otherwise pad every row to the largest neighbourhood)
    d = np.linalg.norm(points[ids] - points[rows], axis=1)
    order = np.lexsort((d, rows))
    rows, ids, lev = rows[order], ids[order], lev[order]
    counts = np.bincount(rows, minlength=n)
    start = np.r_[0, np.cumsum(counts)[:-1]]
    cols = np.arange(len(rows)) - np.repeat(start, counts)
    keep = cols < MAX_NEIGHBOURS
    rows, ids, lev, cols = rows[keep], ids[keep], lev[keep], cols[keep]
    k = int(cols.max()) + 1
    index = np.repeat(np.arange(n)[:, None], k, axis=1)
    level = np.zeros((n, k), dtype=int)
    valid = np.zeros((n, k), dtype=bool)
    index[rows, cols] = ids
    level[rows, cols] = lev
    valid[rows, cols] = True
    return Neighbourhoods(index, level, valid)


def overlap_mask(local: np.ndarray, hood: Neighbourhoods) -> np.ndarray:
    """Reject points whose projection falls inside the region already covered (Fig. 7.6).

    The convex hull of the points collected at earlier breadth-first levels is approximated per
    angular sector by its largest radius; a point of level ``l`` whose projected radius is below
    ``HULL_SHRINK`` times the radius covered at levels ``< l`` in its sector overlaps the
    collected region (the surface folds back under it) and is dropped.

    Parameters
    ----------
    local : (N, K, 3) local coordinates
    hood : Neighbourhoods

    Returns
    -------
    (N, K) bool: True where the point is kept.
    """
    n, k = hood.valid.shape
    r = np.hypot(local[..., 0], local[..., 1])
    sector = ((np.arctan2(local[..., 1], local[..., 0]) + np.pi) / (2 * np.pi) * HULL_SECTORS)
    sector = np.minimum(sector.astype(int), HULL_SECTORS - 1)
    nlev = int(hood.level.max()) + 1
    env = np.zeros((n, nlev + 1, HULL_SECTORS))
    rows = np.repeat(np.arange(n)[:, None], k, axis=1)
    lv = np.where(hood.valid, hood.level, nlev)
    np.maximum.at(env, (rows, lv, sector), np.where(hood.valid, r, 0.0))
    env = np.maximum.accumulate(env[:, :nlev], axis=1)
    before = np.where(lv > 0, env[rows, np.maximum(lv - 1, 0), sector], 0.0)
    return hood.valid & ((lv <= 1) | (r >= HULL_SHRINK * before))


def fit_polynomials(local: np.ndarray, weights: np.ndarray, q_max: int = Q_MAX,
                    cond_max: float = COND_MAX):
    """Weighted least squares with degree selection by the condition number (eq. 7.1-7.4).

    Starting at ``q_max``, the degree is lowered while the condition number of the normal
    matrix ``A`` of eq. (7.4) exceeds ``cond_max`` (points near an algebraic curve of that
    degree, Fig. 7.7), down to degree 1.

    Parameters
    ----------
    local : (N, K, 3) local coordinates (x, y, f) scaled to unit spacing
    weights : (N, K) weights omega (zero for padding)

    Returns
    -------
    coeffs : (N, m) coefficients, zero-padded beyond the chosen degree (m for ``q_max``)
    degree : (N,) int
    cond : (N,) condition number of the chosen A
    """
    b = basis(local[..., 0], local[..., 1], q_max)  # (N, K, m)
    bwt = (b * weights[..., None]).transpose(0, 2, 1)
    a = bwt @ b
    d = (bwt @ local[..., 2, None])[..., 0]
    n, m = d.shape
    degree = np.ones(n, dtype=int)
    cond = np.full(n, np.inf)
    undecided = np.ones(n, dtype=bool)
    for q in range(q_max, 0, -1):
        mq = basis_size(q)
        idx = np.flatnonzero(undecided)
        if len(idx) == 0:
            break
        # A is symmetric positive semi-definite: its 2-norm condition number is the ratio of
        # its extreme eigenvalues (eigvalsh: a quarter of the cost of np.linalg.cond's SVD)
        ev = np.linalg.eigvalsh(a[idx, :mq, :mq])
        with np.errstate(all="ignore"):
            c = np.where(ev[:, 0] > 0, ev[:, -1] / ev[:, 0], np.inf)
        ok = np.isfinite(c) & (c <= cond_max) if q > 1 else np.ones(len(idx), dtype=bool)
        degree[idx[ok]] = q
        cond[idx[ok]] = c[ok]
        undecided[idx[ok]] = False
    coeffs = np.zeros((n, m))
    for q in np.unique(degree):
        idx = np.flatnonzero(degree == q)
        mq = basis_size(q)
        sub = a[idx, :mq, :mq] + 1e-12 * np.eye(mq)  # guards exactly singular degree-1 systems
        coeffs[idx, :mq] = np.linalg.solve(sub, d[idx, :mq, None])[..., 0]
    return coeffs, degree, cond


def choose_scale(values: np.ndarray, spread: np.ndarray, sigma: np.ndarray,
                 kappa: float = ICI_KAPPA, usable: np.ndarray | None = None) -> np.ndarray:
    """Intersection of confidence intervals (Lepski's method): the widest fit whose interval,
    and those of all narrower fits, still share a point.

    A wider Gaussian averages more noise out but bends less with the surface; while the value
    at the origin stays within ``kappa`` standard deviations of all narrower fits, the wider
    fit is no more biased than the noise, so the widest such fit is taken.

    Parameters
    ----------
    values : (P, S) value at the origin of each fit, narrowest first
    spread : (P, S) variance factors (see :func:`smoothing_fit`)
    sigma : (P,) noise standard deviation
    usable : (P, S) bool, optional
        Fits that may be chosen; the widening also stops at the first unusable one (the
        narrowest fit is always taken).

    Returns
    -------
    (P,) int index of the chosen fit.
    """
    half = kappa * sigma[:, None] * np.sqrt(spread)
    lo = np.maximum.accumulate(values - half, axis=1)
    hi = np.minimum.accumulate(values + half, axis=1)
    ok = lo <= hi
    if usable is not None:
        ok &= usable
    ok[:, 0] = True
    ok = np.logical_and.accumulate(ok, axis=1)
    return ok.sum(axis=1) - 1


def choose_fit(values, spread, balance, degree, rss, dof, noise) -> np.ndarray:
    """The fit of each point among ``SCALES + (DETAIL_SCALE,)`` (noise-aware projection).

    The intersection of confidence intervals over ``SCALES`` (:func:`choose_scale`) picks the
    width; near a border of the cloud a wide fit leans on one side only and extrapolates
    across it, so the widening stops there as it does at curvature detail.  Where it reaches
    the widest fit, the degree-4 alternative ``DETAIL_SCALE`` replaces it when its extra
    terms are significant (they lower the weighted residual sum ``rss`` by more than
    ``DEGREE_TEST`` times the ``noise^2 (dof_2 - dof_4)`` they lower it by on noise alone:
    an F-test; ``dof`` also accounts for the two widths) and its value at the point also lies
    within the narrower fits' intervals (on a scan with little noise a fit that leaves them
    bends across a sparse part).

    Parameters
    ----------
    values : (S + 1, P) value at the origin of each fit, in the order of the candidates
    spread, balance, rss, dof : (S + 1, P) of each fit (see :func:`smoothing_fits`)
    degree : (S + 1, P) int, degree of each fit (1 where it fell back to the plane)
    noise : (P,) noise standard deviation, spacings

    Returns
    -------
    (P,) int index of the chosen candidate.
    """
    last = len(values) - 1
    widest = last - 1
    usable = balance < MAX_BALANCE
    pick = choose_scale(values[:last].T, spread[:last].T, noise, usable=usable[:last].T)
    alternative = [*range(widest), last]
    agrees = choose_scale(values[alternative].T, spread[alternative].T, noise,
                          usable=usable[alternative].T) == widest
    gain = rss[widest] - rss[last]
    expected = np.maximum(dof[widest] - dof[last], 0.0) * noise**2
    detail = ((pick == widest) & agrees & (degree[last] == DETAIL_SCALE[1])
              & (gain > DEGREE_TEST * expected))
    return np.where(detail, last, pick)


def _without_sigma(fits):
    """The per-fit arrays of :func:`smoothing_fits` (its noise estimate left out)."""
    return fits[:5] + fits[6:]


def _origin_normals(coeffs: np.ndarray) -> np.ndarray:
    """Unit normals ``(-z_x, -z_y, 1)/|.|`` of polynomial graphs at the local origin, where
    the derivatives are the linear coefficients: ``(P, m)`` -> ``(P, 3)``."""
    nrm = np.stack([-coeffs[:, 1], -coeffs[:, 2], np.ones(len(coeffs))], axis=-1)
    return nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)


class Projector:
    """Projection onto the point-set surface of thesis §7.2.

    Precomputes Cocone connectivity and per point a weighted least-squares polynomial in a
    local coordinate system re-oriented by bisection (Fig. 7.5).

    By default (``smoothing=None``) the fits adapt to the noise in the data: per point the
    noise level is measured from the residuals of a degree-3 fit over about 1.6 spacings and
    pooled over the nearest points.  Where it is below ``CLEAN_NOISE`` spacings the thesis'
    interpolating fit is kept (Gaussian width one spacing, variable degree up to ``q_max`` by
    the condition number), so clean data keeps its accuracy; elsewhere the widest of the
    ``SCALES`` fits (widths 1.6-4.2 spacings, degree 3 then 2) whose value at the point
    stays within the confidence intervals of the narrower fits is taken
    (:func:`choose_scale`), so noise is averaged out where the surface is flat enough and
    curvature detail stops the widening; the widest fit gives way to a narrower degree-4 fit
    where an F-test on the residuals finds terms past the quadratic (:func:`choose_fit`).
    Neighbourhoods are the ``ADAPTIVE_NEIGHBOURS`` nearest points whose oriented normals
    agree (the two sides of a thin part stay apart).

    With a number for ``smoothing`` the thesis' fixed scheme runs: breadth-first
    neighbourhoods (r_c rule and overlap rule, Fig. 7.6) and variable degree at that width.

    Parameters
    ----------
    cloud : PointCloud or (N, 3) array_like
    smoothing : float, optional
        Fixed Gaussian width ``h`` (eq. 7.2) in units of the local spacing (1 is the thesis'
        choice; e.g. 2-3 smooths out measurement noise); ``None`` (default) chooses the width
        per point from the data as described above.
    q_max : int
        Highest polynomial degree (1 ... 6).
    cond_max : float
        Condition-number threshold for the degree reduction.
    fixed_degree : int, optional
        Use this degree everywhere and skip the condition test: an MLS-style ablation (with
        the fixed width ``smoothing``, 1 when not given).
    connectivity : Connectivity, optional
        Reuse a previously computed :func:`cocone_connectivity` (the mesher does); when not
        given, the adaptive mode builds the faster :func:`knn_connectivity` (a projection
        needs no Delaunay tetrahedralisation) and the fixed-width mode Cocone's.

    Attributes
    ----------
    noise : (N,) float or None
        Adaptive mode: the noise standard deviation measured at each point (world units).
    width : (N,) float
        Gaussian width of each point's fit in spacings (1 for clean points).
    degree : (N,) int
        Degree of each point's polynomial.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> v = rng.normal(size=(3000, 3)); v /= np.linalg.norm(v, axis=1, keepdims=True)
    >>> proj = Projector(v)
    >>> q = proj.project(np.array([[0.0, 0.0, 1.2]]))
    >>> bool(abs(np.linalg.norm(q) - 1.0) < 1e-3)
    True
    """

    def __init__(self, cloud, smoothing: float | None = None, q_max: int = Q_MAX,
                 cond_max: float = COND_MAX, fixed_degree: int | None = None,
                 connectivity: Connectivity | None = None):
        if smoothing is not None and not (np.isfinite(smoothing) and smoothing > 0):
            raise ProjectionError(f"smoothing must be a positive number, got {smoothing}")
        if not 1 <= int(q_max) <= 6:
            raise ProjectionError(f"q_max must be between 1 and 6, got {q_max}")
        if fixed_degree is not None and not 1 <= int(fixed_degree) <= int(q_max):
            raise ProjectionError(f"fixed_degree must be between 1 and q_max, got {fixed_degree}")
        self.q_max = int(q_max)
        self.smoothing = None if smoothing is None else float(smoothing)
        adaptive = self.smoothing is None and fixed_degree is None
        if connectivity is not None:
            self.conn = connectivity
        else:
            self.conn = (knn_connectivity(cloud, ADAPTIVE_NEIGHBOURS) if adaptive
                         else cocone_connectivity(cloud))
        self.points = self.conn.points
        self.scale = self.conn.spacing.copy()
        if adaptive:
            self._fit_adaptive(cond_max)
            if connectivity is None:
                # the (N, 80) nearest points served the fits alone: kept, they were a third
                # of a large cloud's memory through the meshing
                self.conn = dataclasses.replace(self.conn, nearest=None)
        else:
            self.smoothing = 1.0 if self.smoothing is None else self.smoothing
            self._fit(fixed_degree, cond_max)
            self.reach = np.full(len(self.points), CUTOFF * self.smoothing)
            self.width = np.full(len(self.points), self.smoothing)
            self.noise = None
        self._median_sets()

    # -- precomputation ------------------------------------------------------------------
    def _fit(self, fixed_degree, cond_max):
        pts, n = self.points, len(self.points)
        h = self.smoothing * self.scale
        hood = collect_neighbourhoods(pts, self.conn.graph, CUTOFF * h)
        rel = pts[hood.index] - pts[:, None, :]  # (N, K, 3)
        dist2 = np.einsum("nkc,nkc->nk", rel, rel)
        weights = np.exp(-dist2 / h[:, None] ** 2)  # eq. (7.2)
        normals = self.conn.normals.copy()
        frames = frames_from_normals(normals)
        coeffs = np.zeros((n, basis_size(self.q_max)))
        degree = np.ones(n, dtype=int)
        cond = np.zeros(n)
        todo = np.arange(n)
        for it in range(MAX_BISECTIONS + 1):
            local = np.einsum("nij,nkj->nki", frames[todo], rel[todo])
            local /= self.scale[todo, None, None]
            keep = overlap_mask(local, Neighbourhoods(hood.index[todo], hood.level[todo],
                                                      hood.valid[todo]))
            w = np.where(keep, weights[todo], 0.0)
            if fixed_degree is None:
                c, q, k = fit_polynomials(local, w, self.q_max, cond_max)
            else:
                c, q, k = fit_polynomials(local, w, int(fixed_degree), np.inf)
                c = np.pad(c, ((0, 0), (0, coeffs.shape[1] - c.shape[1])))
            coeffs[todo], degree[todo], cond[todo] = c, q, k
            nloc = _origin_normals(c)
            tilt = np.arccos(np.clip(nloc[:, 2], -1.0, 1.0))
            bad = tilt > MAX_TILT
            if it == MAX_BISECTIONS or not bad.any():
                break
            # Fig. 7.5: the new z-axis bisects the old one and the polynomial normal
            nworld = np.einsum("nji,nj->ni", frames[todo[bad]], nloc[bad])
            newz = frames[todo[bad], 2] + nworld
            frames[todo[bad]] = frames_from_normals(newz)
            todo = todo[bad]
        self.frames, self.coeffs, self.degree, self.cond = frames, coeffs, degree, cond
        nloc = _origin_normals(coeffs)
        self.normals = np.einsum("nji,nj->ni", frames, nloc)

    def _fit_adaptive(self, cond_max):
        """Noise-aware fits: the scale (and with it the degree) chosen per point from the data.

        Per point: the ``ADAPTIVE_NEIGHBOURS`` nearest points of its own sheet; the noise
        level from the residuals of the narrowest smoothing fit, pooled over the nearest
        points (median); clean points keep the interpolating variable-degree fit of §7.2,
        noisy ones take the widest of the ``SCALES`` fits that the intersection of confidence
        intervals accepts, of degree 4 where the residuals call for it (:func:`choose_fit`).
        The LCS re-orientation of Fig. 7.5 runs on the chosen polynomial.
        """
        pts, n = self.points, len(self.points)
        k = min(ADAPTIVE_NEIGHBOURS, n)
        near = self.conn.nearest
        if near is not None and near.shape[1] >= k:
            index = np.ascontiguousarray(near[:, :k], dtype=np.int32)
        else:
            index, _ = nearest_points(self.conn.tree, pts, k)
        own = np.arange(n, dtype=np.int32)
        if not np.array_equal(index[:, 0], own):
            # points are distinct: the nearest is the point itself (a copy only where a
            # tie put another first, so a caller's connectivity is never written to)
            index = index.copy() if near is not None and np.shares_memory(index, near) \
                else index
            index[:, 0] = own
        normals = self.conn.normals
        # the other side of a thin part is near but faces the other way (oriented normals)
        valid = sheet_mask(normals, index, SHEET_COS)
        frames = frames_from_normals(normals)
        coeffs = np.zeros((n, basis_size(self.q_max)))
        degree = np.ones(n, dtype=int)
        cond = np.zeros(n)
        reach = np.full(n, CUTOFF)
        width = np.ones(n)
        # the narrowest width everywhere: it measures the noise and is the first candidate of
        # the noisy points (the wider ones are fitted for those alone)
        fits = smoothing_fits(pts, index, valid, frames, self.scale, np.arange(n), SCALES[:1],
                              cond_max, noise=True)
        raw = fits[5]
        # residuals also hold the fit's bias where the surface bends sharply (creases, thin
        # parts): there they would pass for noise and open the intervals to the widest fit;
        # creases are lines, so the median over the whole neighbourhood is the noise of the
        # surface around them (and it steadies the estimate from a handful of residuals)
        noise = neighbour_median(raw, index)
        # a scanner's noise varies slowly over a scan; patches of residuals far above the
        # cloud's floor are strongly bent surface (ears, tips) or detail finer than the
        # samples resolve (Lucy's dress folds and feathers: their median residual, 0.2
        # spacings, three times the floor, passed for noise and widened 71 % of the fits to
        # 4.2 spacings, which flattened the detail), not noise: capped, their narrow fits
        # keep the shape.  A cloud with noise has it everywhere, so its floor is near its
        # median (the noisy bunny: 0.30 and 0.33 spacings)
        noise = np.minimum(noise, NOISE_CAP * np.percentile(noise, NOISE_FLOOR_PERCENTILE))
        self.noise = noise * self.scale
        todo = np.arange(n)
        for it in range(MAX_BISECTIONS + 1):
            # in blocks: the wider fits' (4, P, 15) candidates and their copies are bounded
            # by the block, not the cloud (each point's fit is its own: the same results)
            for lo in range(0, len(todo), FIT_BLOCK):
                part = slice(lo, lo + FIT_BLOCK)
                block = None if it > 0 else tuple(f[part] if f.ndim == 1 else f[:, part]
                                                  for f in fits)
                self._choose(todo[part], index, valid, frames, noise[todo[part]], cond_max,
                             coeffs, degree, cond, reach, width, block)
            fits = None
            nloc = _origin_normals(coeffs[todo])
            bad = np.arccos(np.clip(nloc[:, 2], -1.0, 1.0)) > MAX_TILT
            if it == MAX_BISECTIONS or not bad.any():
                break
            # Fig. 7.5: the new z-axis bisects the old one and the polynomial normal
            nworld = np.einsum("nji,nj->ni", frames[todo[bad]], nloc[bad])
            frames[todo[bad]] = frames_from_normals(frames[todo[bad], 2] + nworld)
            todo = todo[bad]
        self.frames, self.coeffs, self.degree, self.cond, self.reach, self.width = (
            frames, coeffs, degree, cond, reach, width)
        self.normals = np.einsum("nji,nj->ni", frames, _origin_normals(coeffs))

    def _choose(self, ids, index, valid, frames, noise, cond_max, coeffs, degree, cond, reach,
                width, fits=None):
        """Fit points ``ids`` in ``frames`` (or take ``fits`` of them) and store the chosen
        fits (:meth:`_fit_adaptive`)."""
        clean = noise < CLEAN_NOISE
        noisy = ids[~clean]
        if len(noisy):
            candidates = SCALES + (DETAIL_SCALE,)
            if fits is None:
                fits = _without_sigma(smoothing_fits(self.points, index, valid, frames,
                                                     self.scale, noisy, candidates, cond_max,
                                                     noise=True))
            else:
                # ``fits`` holds the narrowest width of all points ``ids`` (axis 1)
                wider = smoothing_fits(self.points, index, valid, frames, self.scale, noisy,
                                       candidates[1:], cond_max, noise=True)
                fits = tuple(np.concatenate([f[:, ~clean], w]) for f, w in
                             zip(_without_sigma(fits), _without_sigma(wider), strict=True))
            c, q, kc, spread, balance, rss, dof = fits
            pick = choose_fit(c[:, :, 0], spread, balance, q, rss, dof, noise[~clean])
            rows = np.arange(len(noisy))
            coeffs[noisy] = 0.0
            coeffs[noisy, :c.shape[2]] = c[pick, rows]
            degree[noisy], cond[noisy] = q[pick, rows], kc[pick, rows]
            width[noisy] = np.array([w for w, _ in candidates])[pick]
            # the foot stays within CUTOFF spacings as for the interpolating fits: wider
            # feet let queries beyond a border of the cloud slide far along the extrapolation
            reach[noisy] = CUTOFF
        sel = ids[clean]
        if len(sel):
            c, q, kc = variable_degree_fits(self.points, index, valid, frames, self.scale, sel,
                                            CLEAN_NEIGHBOURS, self.q_max, cond_max)
            coeffs[sel] = c
            degree[sel], cond[sel], reach[sel], width[sel] = q, kc, CUTOFF, 1.0

    def _median_sets(self):
        """Each point with its nearest graph neighbours: ``(N, MEDIAN_NEIGHBOURS)`` ids."""
        self.median_sets = nearest_in_rows(self.conn.graph, MEDIAN_NEIGHBOURS)

    # -- queries ---------------------------------------------------------------------------
    def principal_curvatures(self) -> np.ndarray:
        """Principal curvatures ``(N, 2)`` (world units, ``k1 >= k2`` signed along ``normals``)
        of the local polynomial at each input point's foot point."""
        c, s = self.coeffs, self.scale
        # Monge patch z = p(x, y): first and second derivatives at the origin (scaled units)
        zx, zy, zxx, zxy, zyy = c[:, 1], c[:, 2], 2 * c[:, 3], c[:, 4], 2 * c[:, 5]
        g = 1.0 + zx**2 + zy**2
        k_gauss = (zxx * zyy - zxy**2) / g**2
        k_mean = ((1 + zx**2) * zyy - 2 * zx * zy * zxy + (1 + zy**2) * zxx) / (2 * g**1.5)
        disc = np.sqrt(np.maximum(k_mean**2 - k_gauss, 0.0))
        return np.stack([k_mean + disc, k_mean - disc], axis=1) / s[:, None]

    def project_with_normals(self, points, normal_hint=None):
        """Project points and return the surface normals there.

        Parameters
        ----------
        points : (M, 3) array_like

        normal_hint : (M, 3) array_like, optional
            Approximate normals at the queries: the nearest input point whose normal agrees
            (positive dot product) is used, so that a query near a thin sheet is projected
            onto its own side, not onto the back of the sheet.

        Returns
        -------
        positions : (M, 3) component-wise median of the projections onto the polynomials of the
            nearest input point and its nearest graph neighbours (§7.2).
        normals : (M, 3) unit normals, oriented like the input's Cocone normals.
        """
        r = np.asarray(points, dtype=np.float64)
        if r.ndim != 2 or r.shape[1] != 3:
            raise ProjectionError(f"points must have shape (M, 3), got {r.shape}")
        if not np.all(np.isfinite(r)):
            raise ProjectionError("points to project contain NaN or infinite coordinates")
        if len(r) == 0:
            return np.empty((0, 3)), np.empty((0, 3))
        hint = None if normal_hint is None else np.asarray(normal_hint, dtype=np.float64)
        pos, nrm, nearest = self._median_projection(r, hint)
        # the median of projections spread along a curved surface lies off it (by about
        # spread^2 / 8R); queries from far away, whose projections spread, are projected once
        # more from the median, where the polynomials agree
        far = np.linalg.norm(pos - r, axis=1) > FAR_SPACINGS * self.scale[nearest]
        if far.any():
            pos[far], nrm[far], _ = self._median_projection(
                pos[far], None if hint is None else hint[far])
        return pos, nrm

    def _median_projection(self, r, hint=None):
        if hint is None:
            _, nearest = tree_query(self.conn.tree, r)
        else:
            _, cand = tree_query(self.conn.tree, r, min(HINT_CANDIDATES, len(self.points)))
            agree = np.einsum("mkc,mc->mk", self.normals[cand], hint) > 0
            first = np.where(agree.any(axis=1), np.argmax(agree, axis=1), 0)
            nearest = cand[np.arange(len(r)), first]
        # one compiled call projects onto the k polynomials and takes the medians (NumPy's
        # sorts of the (M, k, 3) projections cost as much as the projections)
        pos, nrm = project_median(self.points, self.frames, self.scale, self.coeffs,
                                  self.degree, self.reach, self.median_sets[nearest], r,
                                  PROJECTION_ITERATIONS)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        return pos, nrm, nearest

    def project(self, points) -> np.ndarray:
        """Project ``(M, 3)`` points onto the local surfaces; returns ``(M, 3)`` (§7.2)."""
        return self.project_with_normals(points)[0]
