"""NumPy reference of direct volume rendering (emission-absorption), the rules of
``compute/kernels/dvr.cl`` done the slow way, for any field with a value and a gradient.

Rules (the kernel follows them to float32 rounding):

- each ray is cut to the data box and the kept side of every clip plane
  (:func:`~splineviz.core.raycast_reference.ray_intervals`) and at its stop parameter (an
  embedded isosurface's hit or an opaque mesh);
- samples at ``t0 + (k + 1/2) dt`` for ``k = 0 .. ceil((t1 - t0) / dt - 1/2) - 1``, ``dt`` in
  world units;
- RGBA from the transfer function's table; opacity corrected for the step:
  ``1 - (1 - a) ** alpha_exp`` with ``alpha_exp = dt / unit`` (the table's opacities are per
  :data:`~splineviz.core.transfer_function.UNIT_STEP` voxels);
- shading (optional): headlight Phong on the normalised gradient, two sided, with the ray
  casters' material constants: ``rgb (AMBIENT + DIFFUSE c) + SPECULAR c^SHININESS``,
  ``c = |n . d|`` (1 where the gradient vanishes);
- front-to-back: ``C += (1 - A) a rgb``, ``A += (1 - A) a``, stopping once ``A`` reaches
  :data:`ERT_ALPHA` (early ray termination);
- the stop colour (premultiplied by its alpha) composited behind what was accumulated;
- depth: the window depth of the first sample where ``A`` reaches :data:`DEPTH_ALPHA`, else
  the stop's depth, else 1 (the far plane).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splineviz.core.camera import Camera, parse_size
from splineviz.core.raycast_reference import (
    AMBIENT,
    DIFFUSE,
    SHININESS,
    SPECULAR,
    normalize_clip_planes,
    ray_intervals,
)
from splineviz.core.transfer_function import UNIT_STEP, TransferFunction

#: accumulated opacity at which a ray stops (early ray termination)
ERT_ALPHA = 0.995
#: accumulated opacity at which a ray's depth is taken: the frame's depth for compositing
#: with geometry (drawn later geometry is hidden where the rendering is at least this opaque)
DEPTH_ALPHA = 0.5


@dataclass
class DVRFrame:
    """One volume-rendered image.

    Attributes
    ----------
    rgba : (H, W, 4) float32
        Accumulated colour, premultiplied by its opacity, and the opacity.
    depth : (H, W) float32
        OpenGL window depth (see the module), 1 where nothing reached :data:`DEPTH_ALPHA`.
    color : (H, W, 4) uint8
        ``rgba`` composited over the background, opaque.
    """

    rgba: np.ndarray
    depth: np.ndarray
    color: np.ndarray


def _cos(grad, directions):
    """|n . d| of the normalised gradients (N, 3) and unit rays (N, 3); 1 where the gradient
    vanishes."""
    gl = np.linalg.norm(grad, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(gl > 0, np.abs(np.einsum("nk,nk->n", grad, directions)) / gl, 1.0)


def shade(rgb, grad, directions, weight=None):
    """Headlight Phong of colours (N, 3) with gradients (N, 3) along unit rays (N, 3).

    ``weight`` (N,): the colours are premultiplied by it (a pre-integrated segment's
    opacity): the specular term is scaled by it and the result bounded by it."""
    cs = _cos(grad, directions)
    w = np.ones(len(rgb)) if weight is None else np.asarray(weight, np.float64)
    out = rgb * (AMBIENT + DIFFUSE * cs)[:, None] + (SPECULAR * cs**SHININESS * w)[:, None]
    return np.clip(out, 0.0, w[:, None])


def reference_dvr(value_gradient, bounds, spacing, camera: Camera, size, tf: TransferFunction,
                  step: float = 0.5, shaded: bool = True, clip_planes=(), stop=None,
                  background=(0.0, 0.0, 0.0), exact_tf: bool = False,
                  preintegrated: bool = False) -> DVRFrame:
    """Volume-render a field by the rules of the module.

    Parameters
    ----------
    value_gradient : callable
        (N, 3) world points -> (values (N,), world gradients (N, 3)), e.g. a spline's
        ``value_gradient`` or an analytic function's.
    bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
        The data box.
    spacing : (3,) float
        Grid spacing: the unit of ``step`` and of the table's opacities is its smallest
        entry.
    camera : Camera
    size : (width, height) or "WxH"
    tf : TransferFunction
    step : float
        Sample distance in voxels of the smallest spacing.
    shaded : bool
    clip_planes : sequence of (origin, normal)
    stop : (t (H, W), rgba (H, W, 4), depth (H, W)), optional
        Per ray: where it ends (inf: nowhere), the straight colour and opacity there and its
        window depth.
    background : RGB in [0, 1]
    exact_tf : bool
        Map values through the transfer function's points instead of its table (the
        analytic reference image).
    preintegrated : bool
        Composite the segment from the previous sample (``t - dt``, clamped into the box)
        to each sample from :meth:`TransferFunction.preintegrated`; shading scales its
        colour as a sample's and adds the specular term times its opacity, at most its
        opacity.

    Returns
    -------
    DVRFrame
    """
    w, h = parse_size(size)
    unit = float(np.min(spacing)) * UNIT_STEP
    dt = step * float(np.min(spacing))
    alpha_exp = dt / unit
    origin, dirs = camera.rays((w, h))
    d = dirs.reshape(-1, 3)
    t0, t1 = ray_intervals(origin, d, bounds, normalize_clip_planes(clip_planes))
    if stop is not None:
        t1 = np.minimum(t1, np.asarray(stop[0], np.float64).ravel())
    n = np.where(t0 < t1, np.ceil((t1 - t0) / dt - 0.5), 0).astype(np.int64)
    n = np.maximum(n, 0)
    acc = np.zeros((len(d), 3))
    alpha = np.zeros(len(d))
    depth = np.ones(len(d))
    has_depth = np.zeros(len(d), bool)
    lookup = tf.evaluate if exact_tf else tf.lookup
    clip_range = camera.fit_clipping_range(bounds)
    lo = np.asarray(bounds, np.float64)[:, 0]
    hi = np.asarray(bounds, np.float64)[:, 1]
    for k in range(int(n.max(initial=0))):
        live = np.flatnonzero((k < n) & (alpha < ERT_ALPHA))
        if not len(live):
            break
        t = t0[live] + (k + 0.5) * dt
        pts = np.clip(origin + t[:, None] * d[live], lo, hi)
        v, g = value_gradient(pts)
        if preintegrated:
            prev = np.clip(origin + (t - dt)[:, None] * d[live], lo, hi)
            c = tf.preintegrated_lookup(value_gradient(prev)[0], v, alpha_exp)
            a = c[:, 3]
            rgb = c[:, :3]
            if shaded:
                rgb = shade(rgb, g, d[live], weight=a)
            # straight colour: the compositing below multiplies by the opacity again
            rgb = rgb / np.where(a > 0, a, 1.0)[:, None]
        else:
            c = lookup(v)
            rgb = shade(c[:, :3], g, d[live]) if shaded else c[:, :3]
            a = 1.0 - np.power(1.0 - np.clip(c[:, 3], 0.0, 1.0), alpha_exp)
        wgt = (1.0 - alpha[live]) * a
        acc[live] += wgt[:, None] * rgb
        alpha[live] += wgt
        first = live[(~has_depth[live]) & (alpha[live] >= DEPTH_ALPHA)]
        if len(first):
            depth[first] = np.clip(camera.window_depth(origin + (t0[first] + (k + 0.5) * dt)
                                                       [:, None] * d[first], clip_range),
                                   0.0, 1.0)
            has_depth[first] = True
    if stop is not None:
        ts = np.asarray(stop[0], np.float64).ravel()
        srgba = np.asarray(stop[1], np.float64).reshape(-1, 4)
        sdepth = np.asarray(stop[2], np.float64).ravel()
        behind = np.isfinite(ts) & (alpha < ERT_ALPHA)
        rest = (1.0 - alpha[behind]) * srgba[behind, 3]
        acc[behind] += rest[:, None] * srgba[behind, :3]
        alpha[behind] += rest
        take = behind & ~has_depth
        depth[take] = sdepth[take]
    rgba = np.concatenate([acc, alpha[:, None]], axis=1).reshape(h, w, 4)
    out = np.clip(acc + (1.0 - alpha)[:, None] * np.asarray(background, np.float64), 0, 1)
    color = np.empty((h, w, 4), np.uint8)
    color[..., :3] = np.rint(out * 255.0).reshape(h, w, 3).astype(np.uint8)
    color[..., 3] = 255
    return DVRFrame(rgba.astype(np.float32), depth.reshape(h, w).astype(np.float32), color)
