"""Sharp creases of scanned parts: detection from two-plane fits and the feature-preserving
projection of a mesh onto them (issue 31, part 3).

Conventions: input points ``(N, 3)`` float64 of a
:class:`~splineviz.pointcloud.projection.Projector`; mesh ``vertices (V, 3)`` float64 and
``faces (F, 3)`` int, counter-clockwise seen from the normal side.

The local polynomials of the projection are smooth: across a crease of a machined part they
round the edge, and the advancing front's vertices, put on that rounded surface, cut a band
about one triangle wide across every edge (a bevel with wrong normals).  As robust MLS and
feature-preserving projections do, a neighbourhood is tested for two sides: where a quadric
leaves residuals well above the noise but two planes, split by k-planes clustering, fit it,
the surface there is the union of two half-planes meeting on their intersection line.  Mesh
vertices near that line are put on it, the others of the neighbourhood on their own side's
plane, and edges are flipped so that the mesh's edges run along the line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splineviz.pointcloud.cocone import tree_query
from splineviz.pointcloud.projection import NOISE_FLOOR_PERCENTILE
from splineviz.pointcloud.quality import radius_ratios
from splineviz.pointcloud.relaxation import (
    FLIP_QUALITY_KEEP,
    border_vertices,
    face_normals,
    undo_spoiling_moves,
)

#: input points per neighbourhood of a clean scan: about three spacings around a vertex, so
#: a vertex of the bevel (within an edge length, at least 1.5 spacings, of the crease) sees
#: both sides
CREASE_NEIGHBOURS = 32
#: noisy scans: the neighbourhoods grow with the noise floor, by ``CREASE_NEIGHBOURS`` per
#: this many spacings of noise, up to ``MAX_CREASE_NEIGHBOURS``: the smooth fits average the
#: noise over up to 4.2 spacings, and planes through 16 points per side placed vertices worse
#: than they (airplane at 0.5 % noise, 0.46 spacings: the moved vertices' mean distance to the
#: true surface rose from 0.26 to 0.32 spacings)
NOISE_PER_NEIGHBOURS = 0.12
MAX_CREASE_NEIGHBOURS = 96
#: a neighbourhood is a crease candidate when a quadric leaves a residual (RMS) above this
#: many times the cloud's noise floor plus ``QUADRIC_FLOOR`` spacings (a noisy flat face's
#: quadric leaves about 0.8 of its noise: 32 points, 6 coefficients)
QUADRIC_NOISE = 1.2
#: (clean scans have no noise to measure against)
QUADRIC_FLOOR = 0.05
#: the wedge of the two sides must explain the points this much better (RMS ratio, the
#: noise's share taken off both residuals: :func:`_explains_better`) than one quadric: a
#: smooth bend is a quadric, a crease is not (a cube with 0.57 spacings of noise: 0.7 found
#: 58 % of the queries on its edges and none of 2000 on its faces; 0.8 found 65 %, and 0.25 %
#: of the faces' queries)
PLANES_GAIN = 0.7
#: ... and leave no more than this many noise levels plus ``QUADRIC_FLOOR`` spacings
PLANES_NOISE = 2.0
#: smallest angle between the two planes' (oriented) normals of a crease: gentler bends are
#: left to the smooth fits (two planes fitted to a noisy flat face's points, 0.29 spacings
#: of noise, are 20-29 degrees apart)
MIN_ANGLE = np.deg2rad(40.0)
#: each side holds at least this fraction of the neighbourhood (a few outliers past an edge
#: are no side)
MIN_SHARE = 0.15
#: the rounding test (:func:`_rounded`) looks at the points within this many spacings of
#: the line ...
NEAR_LINE = 0.7
#: ... needs at least this many of them ...
MIN_NEAR = 4
#: ... and takes a mean height past this many standard errors for a fillet (the bench's
#: airplane has rounded edges only; at 0.25 % noise 110 of its vertices were moved onto
#: wedges, all farther from the true surface, 0.17 to 0.25 spacings on average; with the
#: test 48, and the bench's box and bracket keep 98-99 % of their moves)
ROUND_SIGMAS = 2.0
#: crease queries per block of :func:`detect_creases`
CREASE_BLOCK = 2048
#: k-planes iterations (assign points to the nearer plane, refit)
PLANE_ITERATIONS = 4
#: a vertex is put on the crease line when its own side's foot lies within this fraction of
#: its shortest edge of the line
SNAP_EDGE = 0.5
#: two vertices on the line keep at least this fraction of their edge length apart along it
SNAP_SPREAD = 0.5
#: no vertex moves farther than this many spacings: the bevels of the smooth fits are
#: shallower (on the bench's clean box-cylinder the moves' 99th percentile is 0.72 spacings),
#: a longer move follows a wedge fitted to noise or to a corner
MAX_MOVE = 1.0
#: a flip towards the line must leave each new triangle within this angle of its side's plane
FLIP_PLANE_TILT = np.deg2rad(20.0)
#: a move may not leave a triangle with a radius ratio below this (and below
#: ``FLIP_QUALITY_KEEP`` of its old one): on the bunny, whose scan has a few sharp rims, the
#: unguarded moves took the smallest radius ratio from 0.36 to 0.20
SPOIL_RATIO = 0.3
#: passes of the crease flips
FLIP_PASSES = 3


@dataclass(frozen=True)
class Creases:
    """Two-sided neighbourhoods found by :func:`detect_creases`, one row per crease query.

    Attributes
    ----------
    ids : (M,) int, rows of the queries that lie at a crease
    normals : (M, 2, 3) unit normals of the two sides' planes, turned like the projector's
        (oriented) normals
    origin : (M, 3) the point of the crease line nearest the query
    direction : (M, 3) unit direction of the line (``normals[:, 0] x normals[:, 1]``)
    inward : (M, 2, 3) unit directions in each side's plane, across the line, towards that
        side's points
    """

    ids: np.ndarray
    normals: np.ndarray
    origin: np.ndarray
    direction: np.ndarray
    inward: np.ndarray


def _dots(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products ``(M, K)`` of ``a (M, K, 3)`` with ``b (M, 3)`` (a batched
    matrix product: several times faster than the equivalent einsum)."""
    return (a @ b[..., None])[..., 0]


def _wedge_distance2(rel, normals, origin, direction, inward) -> np.ndarray:
    """Squared distances ``(M, K)`` of points ``rel (M, K, 3)`` to the nearer half-plane of
    their row's wedge (see :func:`_wedge`): the distance to a half-plane is the distance to
    its plane where the point lies over it, and grows with the distance past the line."""
    out = None
    rel_o = rel - origin[:, None]
    for s in range(2):
        height = _dots(rel_o, normals[:, s])
        past = np.minimum(_dots(rel_o, inward[:, s]), 0.0)
        d2 = height * height + past * past
        out = d2 if out is None else np.minimum(out, d2)
    return out


def _plane_fits(rel: np.ndarray, w: np.ndarray):
    """Weighted least-squares planes of point sets.

    Parameters
    ----------
    rel : (M, K, 3) points
    w : (M, K) weights (0 or 1)

    Returns
    -------
    normal : (M, 3) unit normals, centroid : (M, 3), rms : (M,) residual
    """
    total = np.maximum(w.sum(axis=1), 1e-300)
    centroid = (w[:, None] @ rel)[:, 0] / total[:, None]
    d = rel - centroid[:, None]
    cov = ((d * w[..., None]).transpose(0, 2, 1) @ d) / total[:, None, None]
    ev, evec = np.linalg.eigh(cov)
    return evec[:, :, 0], centroid, np.sqrt(np.maximum(ev[:, 0], 0.0))


def _quadric_rms(rel: np.ndarray) -> np.ndarray:
    """RMS residual ``(M,)`` of the least-squares quadric ``z = q(x, y)`` over the principal
    plane of each point set ``rel (M, K, 3)``."""
    normal, centroid, _ = _plane_fits(rel, np.ones(rel.shape[:2]))
    d = rel - centroid[:, None]
    helper = np.zeros_like(normal)
    helper[np.arange(len(normal)), np.argmin(np.abs(normal), axis=1)] = 1.0
    ex = np.cross(helper, normal)
    ex /= np.linalg.norm(ex, axis=1, keepdims=True)
    ey = np.cross(normal, ex)
    x, y, z = (_dots(d, e) for e in (ex, ey, normal))
    scale = np.maximum(np.sqrt((x * x + y * y).mean(axis=1)), 1e-300)[:, None]
    x, y = x / scale, y / scale  # unit spread: the normal equations stay well conditioned
    b = np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], axis=2)  # (M, K, 6)
    bt = b.transpose(0, 2, 1)
    c = np.linalg.solve(bt @ b + 1e-9 * np.eye(6), bt @ z[..., None])
    r = z - (b @ c)[..., 0]
    return np.sqrt((r * r).mean(axis=1))


def crease_neighbours(noise: float) -> int:
    """Input points per crease neighbourhood for a noise floor of ``noise`` spacings."""
    grow = max(1.0, noise / NOISE_PER_NEIGHBOURS)
    return int(min(MAX_CREASE_NEIGHBOURS, round(CREASE_NEIGHBOURS * grow)))


def detect_creases(queries: np.ndarray, projector) -> Creases:
    """Find the queries whose neighbourhood of input points is two planes meeting at a crease.

    Per query: its nearest input points (:func:`crease_neighbours`, more in noisier clouds);
    a candidate where a quadric leaves residuals above ``QUADRIC_NOISE`` times the cloud's
    noise floor (the projector's measured noise) plus ``QUADRIC_FLOOR`` spacings; the points
    split by their normals (two clusters seeded by the two most different normals) and then
    by k-planes (each point to the nearer plane, the planes refitted); accepted when the
    planes' oriented normals are ``MIN_ANGLE`` or more apart, each side holds ``MIN_SHARE``
    of the points, the residual of the wedge of the two half-planes, less the noise's share,
    is far below the quadric's (``PLANES_GAIN``, :func:`_explains_better`) and within the
    noise (``PLANES_NOISE``), and the points near its line show no fillet
    (:func:`_rounded`).

    Parameters
    ----------
    queries : (M, 3) float
    projector : Projector

    Returns
    -------
    Creases
    """
    q = np.asarray(queries, dtype=np.float64)
    level = 0.0
    if projector.noise is not None:
        # the measured noise holds the narrow fits' bias too, and that is largest at the
        # creases themselves (a 90 degree edge with 0.29 spacings of noise: 1.4 times the
        # flat faces'); the cloud's floor is the noise of its flat faces
        level = float(np.percentile(projector.noise, NOISE_FLOOR_PERCENTILE))
    k = min(crease_neighbours(level / np.median(projector.scale)), len(projector.points))
    # in blocks: the (B, k, 6) quadric bases and (B, k, 3) neighbourhoods are bounded by the
    # block, not the mesh
    parts = [_detect_block(q[lo:lo + CREASE_BLOCK], projector, k, level)
             for lo in range(0, len(q), CREASE_BLOCK)]
    if not parts:
        return _no_creases()
    starts = range(0, len(q), CREASE_BLOCK)
    return Creases(np.concatenate([c.ids + lo for c, lo in zip(parts, starts, strict=True)]),
                   *(np.concatenate([getattr(c, name) for c in parts])
                     for name in ("normals", "origin", "direction", "inward")))


def _no_creases() -> Creases:
    return Creases(np.empty(0, dtype=np.int64), np.empty((0, 2, 3)), np.empty((0, 3)),
                   np.empty((0, 3)), np.empty((0, 2, 3)))


def _detect_block(q: np.ndarray, projector, k: int, level: float) -> Creases:
    """:func:`detect_creases` of queries ``q (B, 3)`` with ``k`` neighbours and the cloud's
    noise floor ``level`` (world units)."""
    pts = projector.points
    _, index = tree_query(projector.conn.tree, q, k)
    index = np.reshape(index, (len(q), k))
    nearest = index[:, 0]
    spacing = projector.scale[nearest]
    noise = np.zeros(len(q)) if projector.noise is None else projector.noise[nearest]
    rel = pts[index] - q[:, None]
    rms_q = _quadric_rms(rel)
    floor = QUADRIC_FLOOR * spacing
    cand = np.flatnonzero(rms_q > QUADRIC_NOISE * level + floor)
    if len(cand) == 0:
        return _no_creases()
    rel = rel[cand]
    nrm = projector.normals[index[cand]]  # (C, K, 3), oriented alike
    # seeds: the neighbour's normal farthest from the mean normal, then the one farthest from
    # that: across a crease these are two of the sides' own normals
    mean = nrm.mean(axis=1)
    rows = np.arange(len(cand))
    seed_a = nrm[rows, np.argmin(_dots(nrm, mean), axis=1)]
    seed_b = nrm[rows, np.argmin(_dots(nrm, seed_a), axis=1)]
    side = _dots(nrm, seed_a) < _dots(nrm, seed_b)
    for _ in range(PLANE_ITERATIONS):
        w1 = side.astype(float)
        n0, c0, _ = _plane_fits(rel, 1.0 - w1)
        n1, c1, _ = _plane_fits(rel, w1)
        d0 = np.abs(_dots(rel, n0) - np.einsum("cj,cj->c", c0, n0)[:, None])
        d1 = np.abs(_dots(rel, n1) - np.einsum("cj,cj->c", c1, n1)[:, None])
        side = d1 < d0
    w1 = side.astype(float)
    n0, c0, _ = _plane_fits(rel, 1.0 - w1)
    n1, c1, _ = _plane_fits(rel, w1)
    share = np.minimum(w1.sum(axis=1), k - w1.sum(axis=1)) / k
    # the planes' normals turned like the points' (oriented) ones: a thin wedge (a wing's
    # trailing edge) has nearly opposite sides, not nearly parallel ones
    for normal, w in ((n0, 1.0 - w1), (n1, w1)):
        normal *= np.where((_dots(nrm, normal) * w).sum(axis=1) < 0, -1.0, 1.0)[:, None]
    cos = np.einsum("cj,cj->c", n0, n1)
    wedge = _wedge(n0, c0, n1, c1)
    # the residual of the wedge (each point's distance to the nearer half-plane), not of
    # the two planes: assigning each point to the nearer of two whole planes fits noise
    # (a noisy sphere's or flat face's two planes leave 0.6-0.7 of the quadric's residual)
    rms_p = np.sqrt(_wedge_distance2(rel, *wedge).mean(axis=1))
    ok = ((cos <= np.cos(MIN_ANGLE)) & (share >= MIN_SHARE)
          & _explains_better(rms_p, rms_q[cand], level, k)
          & (rms_p <= PLANES_NOISE * noise[cand] + floor[cand])
          & ~_rounded(rel, side, wedge, spacing[cand], rms_p))
    if not ok.any():
        return _no_creases()
    ids = cand[ok]
    normals, origin, direction, inward = (x[ok] for x in wedge)
    return Creases(ids, normals, origin + q[ids], direction, inward)


def _explains_better(rms_p, rms_q, level, k):
    """``(M,)`` bool: the wedge's residual ``rms_p (M,)`` is ``PLANES_GAIN`` of the quadric's
    ``rms_q (M,)`` or less, both less the share of a noise floor of ``level`` that a fit of six
    parameters to ``k`` points leaves, ``level**2 (k - 6) / k``: what the noise leaves, no
    model explains, and at 0.5 % of noise it is most of either residual (a noisy cube's edges:
    33 % of the queries found comparing the whole residuals, 58 % their excess; still none on
    its faces or on noisy spheres)."""
    noise2 = level * level * (k - 6) / k
    excess_q = rms_q * rms_q - noise2
    return (excess_q > 0.0) & (rms_p * rms_p - noise2 <= PLANES_GAIN ** 2 * excess_q)


def _rounded(rel, side, wedge, spacing, rms) -> np.ndarray:
    """``(M,)`` bool: the points near the wedge's line lie on one side of it, by more than
    their noise allows: a rounded edge (a wing's leading edge), not a sharp one.

    A sharp crease's points scatter about both half-planes up to the line; a fillet's lie
    inside the wedge (or outside, at a concave one) where it turns.  The mean signed height
    of the points within ``NEAR_LINE`` spacings of the line is tested against its standard
    error (the wedge's RMS residual over the root of their number) times ``ROUND_SIGMAS``.

    Parameters
    ----------
    rel : (M, K, 3) points, side : (M, K) bool (True: side 1), wedge : see :func:`_wedge`
    spacing : (M,) local spacing, rms : (M,) the wedge's RMS residual
    """
    normals, origin, _, inward = wedge
    rel_o = rel - origin[:, None]
    height = np.where(side, _dots(rel_o, normals[:, 1]), _dots(rel_o, normals[:, 0]))
    across = np.where(side, _dots(rel_o, inward[:, 1]), _dots(rel_o, inward[:, 0]))
    near = np.abs(across) < NEAR_LINE * spacing[:, None]
    count = near.sum(axis=1)
    bias = np.where(near, height, 0.0).sum(axis=1) / np.maximum(count, 1)
    allowed = ROUND_SIGMAS * rms / np.sqrt(np.maximum(count, 1)) + QUADRIC_FLOOR * spacing
    return (count < MIN_NEAR) | (np.abs(bias) > allowed)


def _wedge(n0, c0, n1, c1):
    """The two half-planes of planes ``(n0, c0)`` and ``(n1, c1)`` (unit normals ``(M, 3)``,
    points ``(M, 3)`` on them, the centroids of their sides' points): ``normals (M, 2, 3)``,
    the line's point nearest the origin ``(M, 3)``, its unit direction ``(M, 3)`` and the
    directions ``inward (M, 2, 3)`` from the line towards each centroid within its plane."""
    direction = np.cross(n0, n1)
    direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-300)
    # x = a n0 + b n1 with n0 . x = n0 . c0 and n1 . x = n1 . c1
    cos = np.einsum("cj,cj->c", n0, n1)
    e0, e1 = np.einsum("cj,cj->c", n0, c0), np.einsum("cj,cj->c", n1, c1)
    det = np.maximum(1.0 - cos * cos, 1e-12)
    a, b = (e0 - cos * e1) / det, (e1 - cos * e0) / det
    origin = a[:, None] * n0 + b[:, None] * n1
    inward = []
    for normal, centroid in ((n0, c0), (n1, c1)):
        u = np.cross(direction, normal)
        sign = np.sign(np.einsum("cj,cj->c", centroid - origin, u))
        inward.append(u * np.where(sign == 0, 1.0, sign)[:, None])
    return np.stack([n0, n1], axis=1), origin, direction, np.stack(inward, axis=1)


def wedge_feet(points: np.ndarray, creases: Creases):
    """Nearest points on the two half-planes of each crease (the union of the sides).

    Parameters
    ----------
    points : (M, 3), one per row of ``creases``
    creases : Creases

    Returns
    -------
    foot : (M, 3) nearest point on the union of the half-planes
    side : (M,) int, 0 or 1: the half-plane of the foot
    across : (M,) float >= 0, the foot's distance from the line
    """
    rel = points - creases.origin
    along = np.einsum("mj,mj->m", rel, creases.direction)
    t = np.maximum(np.einsum("mj,msj->ms", rel, creases.inward), 0.0)  # (M, 2)
    feet = (creases.origin + along[:, None] * creases.direction)[:, None] \
        + t[..., None] * creases.inward
    dist = np.linalg.norm(feet - points[:, None], axis=2)
    side = np.argmin(dist, axis=1)
    rows = np.arange(len(points))
    return feet[rows, side], side, t[rows, side]


def _snap(vertices: np.ndarray, faces: np.ndarray, ids: np.ndarray, line: np.ndarray,
          across: np.ndarray) -> np.ndarray:
    """Choose the vertices put on the crease line: nearest the line first, each at least
    ``SNAP_SPREAD`` of its edge length from every neighbour already on it (two vertices of
    one edge across the bevel would meet at one point of the line).

    Parameters
    ----------
    vertices : (V, 3)
    faces : (F, 3) int
    ids : (M,) int, crease vertices
    line : (M, 3), each one's nearest point of its crease line
    across : (M,) float, each one's distance from the line in units of its shortest edge

    Returns
    -------
    (M,) bool, True where the vertex goes onto the line.
    """
    from scipy import sparse

    n = len(vertices)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    adj = sparse.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    adj = (adj + adj.T).tocsr()
    row_of = np.full(n, -1)
    row_of[ids] = np.arange(len(ids))
    snapped = np.zeros(len(ids), dtype=bool)
    # sequential: whether a vertex may go depends on its neighbours' choices (the crease
    # band holds a small share of the vertices)
    for r in np.argsort(across):
        if across[r] >= SNAP_EDGE:
            break
        i = ids[r]
        nb = adj.indices[adj.indptr[i]:adj.indptr[i + 1]]
        rn = row_of[nb]
        on = rn >= 0
        nb, rn = nb[on], rn[on]
        rn_on = snapped[rn]
        if rn_on.any():
            gap = np.linalg.norm(line[rn[rn_on]] - line[r], axis=1)
            edge = np.linalg.norm(vertices[nb[rn_on]] - vertices[i], axis=1)
            if np.any(gap < SNAP_SPREAD * edge):
                continue
        snapped[r] = True
    return snapped


def _interior_edges(faces: np.ndarray, n: int):
    """Edges with two triangles: ``(a, b, c, d, f1, f2)`` arrays, ``f1 = (a, b, c)`` and
    ``f2 = (b, a, d)`` cyclically; and the sorted keys ``min * n + max`` of all edges."""
    f = np.asarray(faces, dtype=np.int64)
    fid = np.repeat(np.arange(len(f)), 3)
    a = f.ravel()
    b = np.roll(f, -1, axis=1).ravel()
    c = np.roll(f, -2, axis=1).ravel()
    key = np.minimum(a, b) * n + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    pair = np.flatnonzero(ks[1:] == ks[:-1])
    h1, h2 = order[pair], order[pair + 1]
    return (a[h1], b[h1], c[h1], c[h2], fid[h1], fid[h2]), np.unique(key)


def crease_flips(vertices: np.ndarray, faces: np.ndarray, on_line: np.ndarray,
                 plane: np.ndarray) -> tuple[np.ndarray, int]:
    """Flip edges that cross a crease into edges along it.

    An interior edge ``(a, b)`` whose two end vertices lie on different sides (their planes'
    normals apart by more than half ``MIN_ANGLE``) and whose two opposite vertices ``c``,
    ``d`` both lie on the line is replaced by ``(c, d)``, when each new triangle lies within
    ``FLIP_PLANE_TILT`` of its side's plane, turns over no triangle and leaves no sliver
    (the pair's smallest radius ratio stays above ``SPOIL_RATIO`` or ``FLIP_QUALITY_KEEP``
    of the old one).

    Parameters
    ----------
    vertices : (V, 3)
    faces : (F, 3) int
    on_line : (V,) bool, vertices on a crease line
    plane : (V, 3) unit normal of each vertex's side plane (NaN where it has none)

    Returns
    -------
    faces : (F, 3) int, flipped copy
    flips : int
    """
    f = np.array(faces, dtype=np.int64)
    n = len(vertices)
    total = 0
    for _ in range(FLIP_PASSES):
        (a, b, c, d, f1, f2), keys = _interior_edges(f, n)
        has_plane = ~np.isnan(plane[:, 0])
        sel = on_line[c] & on_line[d] & ~on_line[a] & ~on_line[b] & has_plane[a] & has_plane[b]
        a, b, c, d, f1, f2 = (x[sel] for x in (a, b, c, d, f1, f2))
        apart = np.einsum("ij,ij->i", plane[a], plane[b]) < np.cos(0.5 * MIN_ANGLE)
        new_key = np.minimum(c, d) * n + np.maximum(c, d)
        fresh = ~np.isin(new_key, keys)
        old = face_normals(vertices, np.stack([a, b, c], axis=1)) \
            + face_normals(vertices, np.stack([b, a, d], axis=1))
        n1 = face_normals(vertices, np.stack([a, d, c], axis=1))
        n2 = face_normals(vertices, np.stack([d, b, c], axis=1))
        tilt = np.cos(FLIP_PLANE_TILT)
        fits = ((np.abs(np.einsum("ij,ij->i", n1, plane[a])) >= tilt)
                & (np.abs(np.einsum("ij,ij->i", n2, plane[b])) >= tilt)
                & (np.einsum("ij,ij->i", n1, old) > 0) & (np.einsum("ij,ij->i", n2, old) > 0))
        q_old = np.minimum(radius_ratios(vertices, np.stack([a, b, c], axis=1)),
                           radius_ratios(vertices, np.stack([b, a, d], axis=1)))
        q_new = np.minimum(radius_ratios(vertices, np.stack([a, d, c], axis=1)),
                           radius_ratios(vertices, np.stack([d, b, c], axis=1)))
        good = (q_new >= SPOIL_RATIO) | (q_new >= FLIP_QUALITY_KEEP * q_old)
        ok = np.flatnonzero(apart & fresh & fits & good)
        # one flip per triangle and per new edge in a pass
        _, first = np.unique(np.concatenate([f1[ok], f2[ok]]), return_index=True)
        once = np.zeros(2 * len(ok), dtype=bool)
        once[first] = True
        ok = ok[once[:len(ok)] & once[len(ok):]]
        _, first = np.unique(new_key[ok], return_index=True)
        ok = ok[np.sort(first)]
        if len(ok) == 0:
            break
        f[f1[ok]] = np.stack([a[ok], d[ok], c[ok]], axis=1)
        f[f2[ok]] = np.stack([d[ok], b[ok], c[ok]], axis=1)
        total += len(ok)
    return f, total


def sharpen(vertices: np.ndarray, faces: np.ndarray, projector):
    """The feature-preserving projection of a mesh: vertices near a detected crease onto its
    line, the other vertices of two-sided neighbourhoods onto their own side's plane, then
    edges flipped to run along the line (:func:`crease_flips`).

    Border vertices stay; a move that turns a triangle by more than a right angle, or leaves
    it a sliver (radius ratio under ``SPOIL_RATIO`` and under ``FLIP_QUALITY_KEEP`` of its
    old one), is undone with the moves of that triangle's other corners.

    Parameters
    ----------
    vertices : (V, 3) float, on the projector's surface
    faces : (F, 3) int
    projector : Projector

    Returns
    -------
    vertices : (V, 3) float64 (a copy)
    faces : (F, 3) int64
    on_line : (V,) bool, the vertices put on a crease line
    flips : int
    """
    v = np.array(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    n = len(v)
    on_line = np.zeros(n, dtype=bool)
    plane = np.full((n, 3), np.nan)
    if len(f) == 0:
        return v, f, on_line, 0
    used = np.zeros(n, dtype=bool)
    used[f.ravel()] = True
    free = np.flatnonzero(used & ~border_vertices(n, f))
    cr = detect_creases(v[free], projector)
    if len(cr.ids) == 0:
        return v, f, on_line, 0
    ids = free[cr.ids]
    foot, side, across = wedge_feet(v[ids], cr)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    length = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    shortest = np.full(n, np.inf)
    np.minimum.at(shortest, e[:, 0], length)
    np.minimum.at(shortest, e[:, 1], length)
    line = foot - across[:, None] * cr.inward[np.arange(len(ids)), side]
    snapped = _snap(v, f, ids, line, across / shortest[ids])
    target = np.where(snapped[:, None], line, foot)
    far = np.linalg.norm(target - v[ids], axis=1) > MAX_MOVE * projector.scale[
        tree_query(projector.conn.tree, v[ids])[1]]
    target[far] = v[ids[far]]
    snapped &= ~far
    moved = v.copy()
    moved[ids] = target
    moved = undo_spoiling_moves(v, moved, f, 0.0, SPOIL_RATIO, FLIP_QUALITY_KEEP)
    kept = np.all(moved[ids] == target, axis=1) & ~far
    on_line[ids[kept & snapped]] = True
    plane[ids[kept]] = cr.normals[np.arange(len(ids)), side][kept]
    faces_out, flips = crease_flips(moved, f, on_line, plane)
    return moved, faces_out, on_line, flips

