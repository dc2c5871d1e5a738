"""Exact cross-section curves of spline isosurfaces.

A cross section is the set where two functions vanish at once: a spline minus its isovalue and
either a plane's signed distance (:func:`plane_section`) or a second spline minus its isovalue
(:func:`surface_intersection`, e.g. two channels or two models of one volume). The curves are
polylines whose every vertex is put onto *both* surfaces by Newton steps with the exact spline
gradients (the minimum-norm step of the two linearised equations), so a vertex is on the
isosurface to rounding, not to the accuracy of a mesh. Segments are subdivided until their
sagitta (distance of the chord midpoint from the curve) is below a tolerance; length and
enclosed area then come from the vertices and the segments' curve midpoints by Richardson
extrapolation (Huygens' arc rule ``(4 (|am| + |mb|) - |ab|) / 3``), which removes the
polyline's O(h^2) error.

Conventions: world coordinates; points ``(M, 3)`` float64. The splines work in their volume's
own frame; an oblique volume's plane is moved into it and its curves back into world
(:mod:`splineviz.core.frame`: a rigid map, so lengths and areas are unchanged). A closed
curve lists each vertex once (the last joins the first). Open curves end where the section
leaves the data box (their end vertices lie on a box face, also on both surfaces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from splineviz.core import frame
from splineviz.core.errors import SplinevizError

#: value tolerance of a curve vertex, relative to the data range of its volume
VALUE_TOL = 1e-9
#: Newton iterations of one projection onto both surfaces
NEWTON_STEPS = 12
#: a Newton step moves at most this many grid steps (a vertex stays on its own sheet)
STEP_LIMIT = 0.5
#: default sagitta tolerance, in grid steps
SAGITTA = 2e-3
#: most samples of the seeding grid (bounds the time on large volumes)
MAX_SEED_SAMPLES = 2_000_000
#: most subdivision rounds (each halves the longest segments)
MAX_ROUNDS = 24


class SectionError(SplinevizError, ValueError):
    """A cross section that cannot be computed (degenerate plane, disjoint volumes)."""


@dataclass(frozen=True, eq=False)
class SectionCurve:
    """One connected cross-section curve.

    Attributes
    ----------
    points : (M, 3) float64 vertices on both surfaces, in curve order
    closed : bool
        Whether the curve is a loop (the last vertex joins the first).
    length : float
        Arc length (world units).
    area : float
        Enclosed area of a closed curve: the norm of its vector area, which is the area of a
        planar loop; NaN for an open curve.
    """

    points: np.ndarray
    closed: bool
    length: float
    area: float


class Level:
    """The function ``s(x) - iso`` of a spline, for the section solvers.

    Parameters
    ----------
    spline : Spline
    iso : float
    """

    def __init__(self, spline, iso: float):
        self.spline = spline
        self.iso = float(iso)
        lo, hi = spline.volume.finite_range
        #: a vertex counts as on the surface within this value distance
        self.tol = VALUE_TOL * max(hi - lo, 1e-300)
        self.lo = np.array([b[0] for b in spline.bounds])
        self.hi = np.array([b[1] for b in spline.bounds])
        self.step = float(np.min(spline.volume.spacing))

    def __call__(self, x):
        """Values ``(N,)`` and gradients ``(N, 3)`` at ``(N, 3)`` points."""
        v, g = self.spline.value_gradient(x)
        return v - self.iso, g


class Plane:
    """The signed distance ``n . (x - origin)`` of a plane (unit normal ``n``)."""

    def __init__(self, origin, normal, scale: float = 1.0):
        n = np.asarray(normal, dtype=np.float64)
        length = float(np.linalg.norm(n))
        if not np.isfinite(length) or length == 0:
            raise SectionError("a section plane needs a nonzero normal")
        self.origin = np.asarray(origin, dtype=np.float64)
        self.normal = n / length
        self.tol = 1e-13 * scale

    def __call__(self, x):
        return (x - self.origin) @ self.normal, np.broadcast_to(self.normal, x.shape)


def _on_face(x, lo, hi):
    """(N, 3) bool: coordinates on the box faces (those stay fixed during projection)."""
    tol = 1e-9 * np.max(hi - lo)
    return (np.abs(x - lo) < tol) | (np.abs(x - hi) < tol)


def project(f1, f2, points, lo, hi, step_limit):
    """Put points onto both ``f1 = 0`` and ``f2 = 0`` by minimum-norm Newton steps.

    Coordinates lying on a face of the box ``[lo, hi]`` keep their value, so a curve end on a
    face slides within the face.

    Parameters
    ----------
    f1, f2 : Level or Plane
    points : (N, 3)
    lo, hi : (3,) the box
    step_limit : float, longest move per step

    Returns
    -------
    x : (N, 3) projected points
    ok : (N,) bool, both residuals within the functions' ``tol``
    """
    x = np.clip(np.array(points, dtype=np.float64, copy=True), lo, hi)
    free = ~_on_face(x, lo, hi)
    ok = np.zeros(len(x), dtype=bool)
    for _ in range(NEWTON_STEPS):
        r1, g1 = f1(x)
        r2, g2 = f2(x)
        ok = (np.abs(r1) <= f1.tol) & (np.abs(r2) <= f2.tol)
        if ok.all():
            break
        g1 = g1 * free
        g2 = g2 * free
        a = np.einsum("nc,nc->n", g1, g1)
        b = np.einsum("nc,nc->n", g1, g2)
        c = np.einsum("nc,nc->n", g2, g2)
        det = a * c - b * b
        good = det > 1e-24 * np.maximum(a * c, 1e-300)
        # the step -J^T (J J^T)^-1 r: the nearest point of the two linearised surfaces
        with np.errstate(divide="ignore", invalid="ignore"):
            w1 = np.where(good, (c * r1 - b * r2) / det, 0.0)
            w2 = np.where(good, (a * r2 - b * r1) / det, 0.0)
        delta = w1[:, None] * g1 + w2[:, None] * g2
        norm = np.linalg.norm(delta, axis=1)
        scale = np.minimum(1.0, step_limit / np.maximum(norm, 1e-300))
        x = np.clip(x - delta * scale[:, None], lo, hi)
    else:
        r1, _ = f1(x)
        r2, _ = f2(x)
        ok = (np.abs(r1) <= f1.tol) & (np.abs(r2) <= f2.tol)
    return x, ok


def _box(*levels):
    lo = np.max([lv.lo for lv in levels], axis=0)
    hi = np.min([lv.hi for lv in levels], axis=0)
    if np.any(hi < lo):
        raise SectionError("the two volumes do not overlap")
    return lo, hi


def _extend_to_face(f1, f2, curve, lo, hi, step, limit):
    """Append to an open polyline the points where it leaves the box through a face."""
    out = [curve]
    for end, prev in ((0, 1), (-1, -2)):
        if len(curve) < 2:
            break
        p = curve[end]
        t = p - curve[prev]
        t /= max(np.linalg.norm(t), 1e-300)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.where(t > 0, (hi - p) / t, np.where(t < 0, (lo - p) / t, np.inf))
        axis = int(np.argmin(dist))
        if not dist[axis] < 2.5 * step:
            continue
        q = p + dist[axis] * t
        q[axis] = hi[axis] if t[axis] > 0 else lo[axis]
        q, ok = project(f1, f2, q[None], lo, hi, limit)
        if ok[0] and np.linalg.norm(q[0] - p) > 1e-9 * step:
            out.insert(0 if end == 0 else len(out), q)
    return np.concatenate(out)


def _refine(f1, f2, points, closed, lo, hi, sagitta, limit):
    """Subdivide segments until each chord's midpoint is within ``sagitta`` of the curve.

    Returns the vertices ``(M, 3)`` and each segment's curve midpoint ``(M or M - 1, 3)``.
    """
    pts = points
    for _ in range(MAX_ROUNDS):
        nxt = np.roll(pts, -1, axis=0) if closed else pts[1:]
        start = pts if closed else pts[:-1]
        mids, _ok = project(f1, f2, 0.5 * (start + nxt), lo, hi, limit)
        dev = np.linalg.norm(mids - 0.5 * (start + nxt), axis=1)
        split = dev > sagitta
        if not split.any():
            return pts, mids
        # interleave the new midpoints after the segments' first vertices
        m = len(start)
        keep_last = [] if closed else [pts[-1:]]
        order = np.empty((m + int(split.sum()), 3))
        slots = np.arange(m) + np.concatenate([[0], np.cumsum(split)[:-1]])
        order[slots] = start
        order[slots[split] + 1] = mids[split]
        pts = np.concatenate([order, *keep_last])
    nxt = np.roll(pts, -1, axis=0) if closed else pts[1:]
    start = pts if closed else pts[:-1]
    mids, _ok = project(f1, f2, 0.5 * (start + nxt), lo, hi, limit)
    return pts, mids


def _measure(pts, mids, closed):
    """Length and enclosed area with the polyline's O(h^2) error extrapolated away."""
    nxt = np.roll(pts, -1, axis=0) if closed else pts[1:]
    start = pts if closed else pts[:-1]
    chord = np.linalg.norm(nxt - start, axis=1)
    halves = np.linalg.norm(mids - start, axis=1) + np.linalg.norm(nxt - mids, axis=1)
    length = float(np.sum(4.0 * halves - chord) / 3.0)
    if not closed:
        return length, float("nan")
    centre = pts.mean(axis=0)
    a, b, m = start - centre, nxt - centre, mids - centre
    coarse = 0.5 * np.cross(a, b).sum(axis=0)
    fine = 0.5 * (np.cross(a, m) + np.cross(m, b)).sum(axis=0)
    area = float(np.linalg.norm((4.0 * fine - coarse) / 3.0))
    return length, area


def _finish(f1, f2, polylines, lo, hi, step, sagitta):
    """Project, extend open ends to the box, subdivide and measure the raw polylines."""
    limit = STEP_LIMIT * step
    curves = []
    for raw, closed in polylines:
        pts, ok = project(f1, f2, raw, lo, hi, limit)
        pts = pts[ok]
        if len(pts) < 2:
            continue
        # drop repeated vertices (two raw points that converged to one)
        gap = np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9 * step
        pts = pts[np.r_[True, gap]]
        if closed and len(pts) > 2 and np.linalg.norm(pts[0] - pts[-1]) <= 1e-9 * step:
            pts = pts[:-1]
        if len(pts) < (3 if closed else 2):
            continue
        if not closed:
            pts = _extend_to_face(f1, f2, pts, lo, hi, step, limit)
        pts, mids = _refine(f1, f2, pts, closed, lo, hi, sagitta, limit)
        length, area = _measure(pts, mids, closed)
        curves.append(SectionCurve(pts, closed, length, area))
    return curves


class _AxisAligned:
    """A spline seen as the grid of its volume's own frame (the solvers then run there)."""

    def __init__(self, spline):
        self._spline = spline
        self.volume = _OwnFrame(spline.volume)

    def __getattr__(self, name):
        return getattr(self._spline, name)


class _OwnFrame:
    """A volume without its direction (its samples, range and grid are its own)."""

    direction = None

    def __init__(self, volume):
        self._volume = volume

    def __getattr__(self, name):
        return getattr(self._volume, name)


def _in_world(volume, curves):
    """``curves`` of ``volume``'s own frame with their points in world."""
    return [SectionCurve(frame.to_world(volume, c.points), c.closed, c.length, c.area)
            for c in curves]


def plane_basis(normal):
    """Two unit vectors ``(2, 3)`` spanning the plane with unit ``normal``."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    return np.stack([u, np.cross(n, u)])


def plane_section(spline, iso: float, origin, normal, sagitta: float | None = None):
    """Curves where a plane cuts the isosurface ``s = iso`` of a spline.

    The spline is sampled on a grid in the plane (half a grid step apart), contoured
    (contourpy's marching squares), and every vertex is then projected onto both the plane and
    the isosurface and the segments subdivided (see the module notes).

    Parameters
    ----------
    spline : Spline
    iso : float
    origin : (3,) a point of the plane
    normal : (3,) its normal
    sagitta : float, optional
        Largest distance of a chord's midpoint from the curve; default ``SAGITTA`` grid steps.

    Returns
    -------
    list of SectionCurve
    """
    vol = spline.volume
    if frame.rotation(vol) is not None:
        (origin, normal), = frame.planes_to_volume(
            vol, np.array([[origin, np.asarray(normal, float) / np.linalg.norm(normal)]],
                          dtype=np.float64))
        return _in_world(vol, plane_section(_AxisAligned(spline), iso, origin, normal,
                                            sagitta))
    import contourpy

    level = Level(spline, iso)
    lo, hi = level.lo, level.hi
    plane = Plane(origin, normal, float(np.linalg.norm(hi - lo)))
    basis = plane_basis(plane.normal)
    # the box corners in plane coordinates bound the part of the plane inside the box
    corners = np.array(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij")).reshape(3, -1).T
    centre = plane.origin + ((0.5 * (lo + hi) - plane.origin) @ basis.T) @ basis
    uv = (corners - centre) @ basis.T
    umin, vmin = uv.min(axis=0)
    umax, vmax = uv.max(axis=0)
    h = 0.5 * level.step
    span = max(umax - umin, vmax - vmin, h)
    h = max(h, span / np.sqrt(MAX_SEED_SAMPLES))
    us = np.arange(umin, umax + h, h)
    vs = np.arange(vmin, vmax + h, h)
    grid = centre + us[None, :, None] * basis[0] + vs[:, None, None] * basis[1]  # (nv, nu, 3)
    flat = grid.reshape(-1, 3)
    inside = np.all((flat >= lo - 1e-12) & (flat <= hi + 1e-12), axis=1)
    z = np.full(len(flat), np.nan)
    if inside.any():
        z[inside] = level.spline.evaluate(flat[inside]) - level.iso
    gen = contourpy.contour_generator(us, vs, z.reshape(grid.shape[:2]), name="serial",
                                      line_type="Separate", corner_mask=True)
    polylines = []
    for line in gen.lines(0.0):
        closed = len(line) > 3 and np.allclose(line[0], line[-1])
        if closed:
            line = line[:-1]
        pts3 = centre + line[:, :1] * basis[0] + line[:, 1:] * basis[1]
        polylines.append((pts3, closed))
    sag = SAGITTA * level.step if sagitta is None else float(sagitta)
    return _finish(level, plane, polylines, lo, hi, level.step, sag)


def _trace(f1, f2, seed, lo, hi, step, limit):
    """Follow the curve from ``seed`` both ways; returns ``(points (M, 3), closed)``."""

    def tangent(x):
        _, g1 = f1(x[None])
        _, g2 = f2(x[None])
        t = np.cross(g1[0], g2[0])
        n = np.linalg.norm(t)
        return t / n if n > 0 else None

    halves = []
    t0 = tangent(seed)
    if t0 is None:
        return seed[None], False
    for sign in (1.0, -1.0):
        pts = [seed]
        x, t = seed, sign * t0
        h = step
        closed = False
        for _ in range(100_000):
            q, ok = project(f1, f2, (x + h * t)[None], lo, hi, limit)
            moved = np.linalg.norm(q[0] - x)
            if not ok[0] or moved < 0.3 * h or moved > 2.0 * h:
                if h < 1e-3 * step:
                    break
                h *= 0.5
                continue
            x_new = q[0]
            t_new = tangent(x_new)
            if t_new is None:
                break
            if t_new @ t < 0:
                t_new = -t_new
            pts.append(x_new)
            # back at the seed after going round: a loop
            if len(pts) > 3 and np.linalg.norm(x_new - seed) < 1.5 * h:
                closed = True
                break
            if _on_face(x_new[None], lo, hi).any():
                break
            x, t = x_new, t_new
            h = min(step, 1.5 * h)
        if closed:
            return np.array(pts), True
        halves.append(np.array(pts))
    return np.concatenate([halves[1][::-1], halves[0][1:]]), False


def surface_intersection(spline1, iso1: float, spline2, iso2: float,
                         sagitta: float | None = None):
    """Curves where the isosurfaces ``s1 = iso1`` and ``s2 = iso2`` of two splines meet.

    Seeds are the grid cells (of the finer of the two grids, within the box both volumes
    cover) where both splines cross their isovalues; from each seed not yet on a traced curve
    the curve is followed by predictor (along ``grad s1 x grad s2``) and corrector (Newton onto
    both surfaces) steps of one grid step, then refined and measured as in
    :func:`plane_section`. Components smaller than a grid cell can be missed.

    Parameters
    ----------
    spline1, spline2 : Spline
    iso1, iso2 : float
    sagitta : float, optional

    Returns
    -------
    list of SectionCurve
    """
    vol1, vol2 = spline1.volume, spline2.volume
    if frame.rotation(vol1) is not None or frame.rotation(vol2) is not None:
        if not np.allclose(frame.world_matrix(vol1), frame.world_matrix(vol2), rtol=0,
                           atol=1e-9 * max(1.0, *np.abs(vol1.origin))):
            raise SectionError("the two isosurfaces' volumes lie in differently turned frames "
                               "(their directions or origins differ); their intersection is "
                               "computed only for volumes that share one frame")
        return _in_world(vol1, surface_intersection(_AxisAligned(spline1), iso1,
                                                    _AxisAligned(spline2), iso2, sagitta))
    f1, f2 = Level(spline1, iso1), Level(spline2, iso2)
    lo, hi = _box(f1, f2)
    step = min(f1.step, f2.step)
    n = np.maximum(np.ceil((hi - lo) / step).astype(int) + 1, 2)
    while np.prod(n) > MAX_SEED_SAMPLES:
        n = np.maximum((n + 1) // 2, 2)
    axes = [np.linspace(lo[i], hi[i], n[i]) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    v1 = (spline1.evaluate(grid) - f1.iso).reshape(n)
    v2 = (spline2.evaluate(grid) - f2.iso).reshape(n)

    def crossing(v):
        corners = np.stack([v[a:a + n[0] - 1, b:b + n[1] - 1, c:c + n[2] - 1]
                            for a in (0, 1) for b in (0, 1) for c in (0, 1)])
        return (corners.min(axis=0) <= 0) & (corners.max(axis=0) >= 0)

    cells = np.argwhere(crossing(v1) & crossing(v2))
    cell = (hi - lo) / (n - 1)
    seeds, ok = project(f1, f2, lo + (cells + 0.5) * cell, lo, hi, STEP_LIMIT * step)
    seeds = seeds[ok]
    sag = SAGITTA * step if sagitta is None else float(sagitta)
    limit = STEP_LIMIT * step
    polylines = []
    covered = np.zeros(len(seeds), dtype=bool)
    tree = cKDTree(seeds) if len(seeds) else None
    for i in range(len(seeds)):
        if covered[i]:
            continue
        pts, closed = _trace(f1, f2, seeds[i], lo, hi, step, limit)
        for near in tree.query_ball_point(pts, 1.5 * float(np.max(cell))):
            covered[near] = True
        if len(pts) >= 2:
            polylines.append((pts, closed))
    return _finish(f1, f2, polylines, lo, hi, step, sag)
