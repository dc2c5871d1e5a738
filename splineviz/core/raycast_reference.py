"""NumPy reference ray caster for spline isosurfaces (thesis §6.2, done the slow, exact way).

Used to test the OpenCL kernels and as the fallback when no OpenCL device works. It only uses
the public :class:`~splineviz.core.splines.base.Spline` interface (``evaluate``,
``gradient`` and ``value_gradient``), so it works for every model, including future ones.

Method: each ray is cut to the data box and to the kept side of every clip plane (a convex
set, so one interval ``[t0, t1]``); ``s(x) - iso`` is sampled densely along it (``step``
voxels apart); the first sample interval where the sign changes (or a sample that is exactly
on the surface) brackets the first root, which bisection refines to the resolution of float64.
A pair of roots closer than ``step`` can be missed; the kernels are exact there, and the tests
allow for such grazing rays by the hit/miss agreement threshold.

Conventions: world coordinates; images ``(H, W)`` with row 0 at the top; see
:mod:`splineviz.core.camera`.
"""

from __future__ import annotations

import numpy as np

from splineviz.core.camera import Camera, parse_size
from splineviz.core.errors import SplinevizError
from splineviz.core.material import BACK_COLOR, DEFAULT_MATERIAL, FRONT_COLOR, MATERIALS


class ClipPlaneError(SplinevizError, ValueError):
    """Clip planes that are not (origin, normal) pairs with a non-zero normal."""


#: Phong parameters of the ray casters' headlight model (the default material; the kernels
#: take them as defines from these names)
AMBIENT, DIFFUSE, SPECULAR, SHININESS = MATERIALS[DEFAULT_MATERIAL].astuple()
BACKGROUND = (0.10, 0.10, 0.14)

#: bisection steps: enough to shrink any sampled bracket to float64 resolution
BISECTION_STEPS = 52


class Frame:
    """One rendered image of an isosurface (docs/api.md, ``RayCaster.render``).

    Attributes
    ----------
    hit : (H, W) bool
    position : (H, W, 3) float64 world position of the first hit, NaN where no hit
    normal : (H, W, 3) float64 normalised spline gradient at the hit, NaN where no hit
    depth : (H, W) float32 OpenGL window depth in [0, 1], 1 where no hit
    color : (H, W, 4) uint8 shaded RGBA image
    hessian : (H, W, 3, 3) float64 world Hessian of the spline at the hit, or None
        (only when asked for, and only by the OpenCL ray caster; NaN where no hit)
    gradient_norm : (H, W) float64 |grad s| at the hit, or None (with ``hessian``)

    Notes
    -----
    ``position``, ``normal`` and ``color`` may be given as functions of no argument that
    return the array: they are then called on first access. Drawing a frame needs only its
    colour and depth, so the OpenCL ray caster leaves positions and normals on the device
    until something (picking, colour by, a test) reads them: converting them costs more than
    the kernel that made the frame. A view draws a cell-projected frame from its normals and
    depth alone, so its colours are shaded only when read.
    """

    __slots__ = ("hit", "_position", "_normal", "depth", "_color", "hessian", "gradient_norm")

    def __init__(self, hit, position, normal, depth, color, hessian=None, gradient_norm=None):
        self.hit = hit
        self._position = position
        self._normal = normal
        self.depth = depth
        self._color = color
        self.hessian = hessian
        self.gradient_norm = gradient_norm

    @property
    def position(self) -> np.ndarray:
        if callable(self._position):
            self._position = self._position()
        return self._position

    @position.setter
    def position(self, value) -> None:
        self._position = value

    @property
    def normal(self) -> np.ndarray:
        if callable(self._normal):
            self._normal = self._normal()
        return self._normal

    @normal.setter
    def normal(self, value) -> None:
        self._normal = value

    @property
    def color(self) -> np.ndarray:
        if callable(self._color):
            self._color = self._color()
        return self._color

    @color.setter
    def color(self, value) -> None:
        self._color = value

    def load(self) -> Frame:
        """Read the deferred positions and normals now, in this thread; returns ``self``.

        A viewer calls it in its render worker: read later in the GUI thread, the read-back
        would wait behind the next frame's kernel on the device queue (slider previews were
        ~30 ms later)."""
        self.position, self.normal = self.position, self.normal
        return self


def normalize_clip_planes(clip_planes) -> np.ndarray:
    """Clip planes as a ``(P, 2, 3)`` float64 array of (origin, unit normal).

    A plane keeps the half-space its normal points to: ``dot(x - origin, normal) >= 0``.
    """
    if clip_planes is None:
        return np.zeros((0, 2, 3))
    planes = list(clip_planes)
    if not planes:
        return np.zeros((0, 2, 3))
    try:
        arr = np.array([np.asarray(p, dtype=np.float64).reshape(2, 3) for p in planes])
    except (ValueError, TypeError):
        raise ClipPlaneError(
            "each clip plane must be an (origin, normal) pair of 3-vectors"
        ) from None
    norms = np.linalg.norm(arr[:, 1], axis=1)
    if not np.all(np.isfinite(arr)) or np.any(norms == 0):
        raise ClipPlaneError("clip plane origins and normals must be finite, normals non-zero")
    arr[:, 1] /= norms[:, None]
    return arr


def ray_intervals(origin, directions, bounds, planes) -> tuple[np.ndarray, np.ndarray]:
    """Parameter interval of each ray inside the box and on the kept side of all planes.

    Parameters
    ----------
    origin : (3,) float64
    directions : (N, 3) float64 (any length; t is in units of it)
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
    planes : (P, 2, 3) from :func:`normalize_clip_planes`

    Returns
    -------
    t0, t1 : (N,) float64; the interval is empty where ``t0 > t1``. ``t0 >= 0``.
    """
    d = np.asarray(directions, dtype=np.float64)
    lo = np.asarray(bounds, dtype=np.float64)[:, 0]
    hi = np.asarray(bounds, dtype=np.float64)[:, 1]
    t0 = np.zeros(len(d))
    t1 = np.full(len(d), np.inf)
    for a in range(3):
        da = d[:, a]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta = (lo[a] - origin[a]) / da
            tb = (hi[a] - origin[a]) / da
        par = da == 0
        inside = (lo[a] <= origin[a]) & (origin[a] <= hi[a])
        near = np.where(par, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb))
        far = np.where(par, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb))
        t0 = np.maximum(t0, near)
        t1 = np.minimum(t1, far)
    for p_origin, normal in planes:
        a0 = float(np.dot(origin - p_origin, normal))  # signed distance of the eye
        b = d @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            tc = -a0 / b
        t0 = np.where(b > 0, np.maximum(t0, tc), t0)
        t1 = np.where(b < 0, np.minimum(t1, tc), t1)
        blocked = (b == 0) & (a0 < 0)
        t1 = np.where(blocked, -np.inf, t1)
    return t0, t1


def phong_shade(hit, normal, directions) -> np.ndarray:
    """Headlight Phong shading of a hit image.

    The light sits at the eye, so light and view direction are both ``-d``; shading is two
    sided (``|n . d|``). The face colour tells the sides apart: :data:`FRONT_COLOR` where
    the gradient points away from the viewer (``n . d > 0``), else :data:`BACK_COLOR`.

    Parameters
    ----------
    hit : (H, W) bool
    normal : (H, W, 3) unit normals (ignored where not hit)
    directions : (H, W, 3) unit ray directions

    Returns
    -------
    (H, W, 4) uint8 RGBA, opaque.
    """
    h, w = hit.shape
    ndl = np.einsum("hwk,hwk->hw", np.nan_to_num(normal), directions)
    cos = np.abs(ndl)
    base = np.where((ndl > 0)[..., None], np.asarray(FRONT_COLOR), np.asarray(BACK_COLOR))
    rgb = base * (AMBIENT + DIFFUSE * cos)[..., None] + (SPECULAR * cos**SHININESS)[..., None]
    rgb = np.where(hit[..., None], rgb, np.asarray(BACKGROUND))
    out = np.empty((h, w, 4), dtype=np.uint8)
    out[..., :3] = np.rint(np.clip(rgb, 0.0, 1.0) * 255.0).astype(np.uint8)
    out[..., 3] = 255
    return out


def first_roots(spline, origin, directions, t0, t1, isovalue, step_t):
    """First root of ``g(t) = s(origin + t d) - iso`` in ``[t0, t1]`` for each ray.

    Samples carry the value and the directional derivative ``g'``. A sample interval brackets
    a root when ``g`` changes sign, or when ``g`` keeps its sign but ``g'`` says the curve
    turns back towards zero inside (``g > 0`` with ``g'`` going from - to +, or the mirror
    case): then the turning point is located by bisection on the sign of ``g'`` and, if ``g``
    there has crossed zero, ``[left sample, turning point]`` is the bracket. This catches the
    pair of close roots of a grazing ray that plain sign tests at ``step`` would miss, as
    long as ``g'`` changes sign at most once per step.

    Parameters
    ----------
    spline : Spline
    origin : (3,) float64
    directions : (N, 3) float64
    t0, t1 : (N,) float64 intervals (empty where ``t0 > t1``)
    isovalue : float
    step_t : (N,) float64 sample spacing in units of t

    Returns
    -------
    (N,) float64 ray parameter of the first root, NaN where there is none.
    """
    n = len(directions)
    result = np.full(n, np.nan)
    alive = np.flatnonzero(t0 <= t1)
    if alive.size == 0:
        return result
    batch = 32

    def sample(pts, dirs):
        v, grad = spline.value_gradient(pts)
        return v - isovalue, np.einsum("nk,nk->n", grad, dirs)

    # value and slope at the last sample of the previous batch of each live ray
    t_prev = t0[alive].copy()
    g_prev, s_prev = sample(origin + t_prev[:, None] * directions[alive], directions[alive])
    on = g_prev == 0
    result[alive[on]] = t_prev[on]
    keep = ~on
    alive, t_prev, g_prev, s_prev = alive[keep], t_prev[keep], g_prev[keep], s_prev[keep]
    k0 = 1
    while alive.size:
        m = alive.size
        ks = np.arange(k0, k0 + batch, dtype=np.float64)
        t = np.minimum(t0[alive, None] + ks[None, :] * step_t[alive, None], t1[alive, None])
        dirs = np.broadcast_to(directions[alive, None, :], (m, batch, 3))
        pts = origin + t[..., None] * dirs
        g, sl = sample(pts.reshape(-1, 3), dirs.reshape(-1, 3))
        g, sl = g.reshape(t.shape), sl.reshape(t.shape)
        t_left = np.concatenate([t_prev[:, None], t[:, :-1]], axis=1)
        g_left = np.concatenate([g_prev[:, None], g[:, :-1]], axis=1)
        s_left = np.concatenate([s_prev[:, None], sl[:, :-1]], axis=1)
        change = (g == 0) | ((g_left < 0) != (g < 0))
        t_right = t.copy()
        # same sign at both ends, but the slope turns towards zero inside the interval
        turn = ~change & (t > t_left) & (
            ((g_left > 0) & (s_left < 0) & (sl > 0)) | ((g_left < 0) & (s_left > 0) & (sl < 0))
        )
        if turn.any():
            r, k = np.nonzero(turn)
            te, ge = _turning_points(spline, origin, directions[alive[r]], t_left[r, k],
                                     t[r, k], s_left[r, k], isovalue)
            crossed = (ge == 0) | ((ge < 0) != (g_left[r, k] < 0))
            change[r[crossed], k[crossed]] = True
            t_right[r[crossed], k[crossed]] = te[crossed]
            g[r[crossed], k[crossed]] = np.where(ge[crossed] == 0, 0.0, 1.0)
        found = change.any(axis=1)
        first = np.argmax(change, axis=1)
        rows = np.flatnonzero(found)
        if rows.size:
            fk = first[rows]
            exact = g[rows, fk] == 0
            t_hi = t_right[rows, fk]
            roots = _bisect(spline, origin, directions[alive[rows]], t_left[rows, fk], t_hi,
                            g_left[rows, fk], isovalue)
            result[alive[rows]] = np.where(exact, t_hi, roots)
        done = found | (t[:, -1] >= t1[alive])
        t_prev, g_prev, s_prev = t[~done, -1], g[~done, -1], sl[~done, -1]
        alive = alive[~done]
        k0 += batch
    return result


def _turning_points(spline, origin, d, t_lo, t_hi, s_lo, isovalue):
    """Bisection on the sign of the directional derivative; returns (t, g(t)) at the end."""
    neg_lo = s_lo < 0
    for _ in range(BISECTION_STEPS // 2):
        mid = 0.5 * (t_lo + t_hi)
        grad = spline.gradient(origin + mid[:, None] * d)
        sm = np.einsum("nk,nk->n", grad, d)
        same = (sm < 0) == neg_lo
        t_lo = np.where(same, mid, t_lo)
        t_hi = np.where(same, t_hi, mid)
    # the extremum of g lies in [t_lo, t_hi]; test the end with the smaller |g| side
    cand = np.stack([t_lo, t_hi], axis=1)
    vals = spline.evaluate((origin + cand[..., None] * d[:, None, :]).reshape(-1, 3))
    vals = vals.reshape(-1, 2) - isovalue
    pick = np.argmin(np.abs(vals), axis=1)
    idx = np.arange(len(t_lo))
    return cand[idx, pick], vals[idx, pick]


def _bisect(spline, origin, d, t_lo, t_hi, g_lo, isovalue):
    """Bisection on brackets with ``g(t_lo) = g_lo`` and a sign change in ``[t_lo, t_hi]``."""
    neg_lo = g_lo < 0
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (t_lo + t_hi)
        gm = spline.evaluate(origin + mid[:, None] * d) - isovalue
        zero = gm == 0
        same = ((gm < 0) == neg_lo) & ~zero
        t_lo = np.where(same, mid, t_lo)
        t_hi = np.where(same, t_hi, mid)
        t_lo = np.where(zero, mid, t_lo)
    return 0.5 * (t_lo + t_hi)


def reference_raycast(spline, camera: Camera, size, isovalue: float, clip_planes=(),
                      step: float = 0.25) -> Frame:
    """Render the isosurface ``s = isovalue`` of ``spline`` by dense sampling (see module).

    Parameters
    ----------
    spline : Spline
        Any model; only ``evaluate``, ``value_gradient``, ``bounds`` and ``volume.spacing``
        are used.
    camera : Camera
    size : (width, height) or "WxH"
    isovalue : float
    clip_planes : sequence of (origin, normal)
        Each keeps the side its normal points to.
    step : float
        Sample spacing along a ray in voxels (of the smallest grid spacing).

    Returns
    -------
    Frame
    """
    w, h = parse_size(size)
    if not step > 0:
        raise ValueError(f"step must be positive, got {step}")
    planes = normalize_clip_planes(clip_planes)
    origin, dirs = camera.rays((w, h))
    d = dirs.reshape(-1, 3)
    bounds = np.asarray(spline.bounds, dtype=np.float64)
    t0, t1 = ray_intervals(origin, d, bounds, planes)
    # step voxels measured in index space, whatever the spacing per axis
    spacing = np.asarray(spline.volume.spacing, dtype=np.float64)
    step_t = step / np.linalg.norm(d / spacing, axis=1)
    t = first_roots(spline, origin, d, t0, t1, float(isovalue), step_t)
    hit = np.isfinite(t)
    position = np.full((len(d), 3), np.nan)
    normal = np.full((len(d), 3), np.nan)
    position[hit] = origin + t[hit, None] * d[hit]
    if hit.any():
        _, grad = spline.value_gradient(position[hit])
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            normal[hit] = np.where(norm > 0, grad / norm, 0.0)
    depth = np.ones(len(d), dtype=np.float32)
    clip_range = camera.fit_clipping_range(bounds)
    depth[hit] = np.clip(camera.window_depth(position[hit], clip_range), 0.0, 1.0)
    hit = hit.reshape(h, w)
    normal = normal.reshape(h, w, 3)
    color = phong_shade(hit, normal, dirs)
    return Frame(hit, position.reshape(h, w, 3), normal, depth.reshape(h, w), color)
