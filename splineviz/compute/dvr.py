"""Direct volume rendering of a spline model on the OpenCL device (``kernels/dvr.cl``).

:class:`VolumeRenderer` marches the rays of a frame through the volume, samples the spline
model (trilinear, or a type-6 spline: super-quadratic, cubic-c1) with its exact gradient, maps
values through a :class:`~splineviz.core.transfer_function.TransferFunction` and composites
front to back (the rules are :mod:`splineviz.core.dvr_reference`'s, its NumPy reference).
The device samples and model tables are the isosurface ray caster's
(:class:`~splineviz.compute.raycast.RayCaster`, uploaded once per volume); the kernel reuses
the point-evaluation pieces of ``raycast.cl``. Empty space: per block of
:data:`BLOCK`\\ ^3 voxels the conservative value range of the model (samples a block's points
read, widened by the family's negative weight mass), computed once per volume; a transfer
function change only turns them into per-block leap distances (:func:`leap_distances`: how
far around a block everything is transparent, so a ray crosses a large empty region in a few
leaps, not one per block).

Models whose kernel family has no point evaluation here (``to-quadratic``, plugin families)
are rendered by the NumPy reference (slow; ``stats["path"] == "numpy"``).
"""

from __future__ import annotations

import time

import numpy as np

from splineviz.compute.program import get_kernel, kernel_source
from splineviz.compute.raycast import RayCaster
from splineviz.core import dvr_reference as ref
from splineviz.core import frame as volume_frame
from splineviz.core.camera import Camera, parse_size
from splineviz.core.raycast_reference import normalize_clip_planes
from splineviz.core.splines.boundary import pad_linear
from splineviz.core.transfer_function import (
    PREINT_SIZE,
    TABLE_SIZE,
    UNIT_STEP,
    TransferFunction,
)
from splineviz.core.volume import Volume

#: voxels per axis of an empty-space block (kernels/dvr.cl BLOCK)
BLOCK = 4
#: kernel families whose point evaluation dvr.cl has
DEVICE_FAMILIES = ("trilinear", "type6")


def block_bounds(data: np.ndarray, negmass: float = 0.0,
                 reach: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Conservative (min, max) of the spline over each block of :data:`BLOCK`^3 voxels.

    Block ``b`` holds the index-space points ``u`` with ``floor(u / BLOCK) = b`` (its closed
    box ``[BLOCK b, BLOCK (b + 1)]``); there the model reads samples ``BLOCK b - reach ..
    BLOCK b + BLOCK + reach``: ``reach`` 0 for trilinear cells, 1 for the type-6 stencils (27
    samples around the cube centre nearest ``u``); a ghost layer (linear extrapolation, as
    the device samples) covers the boundary. The range is widened by
    ``negmass`` times its width (the spline is an affine, not convex, combination of the
    samples there). The tighter the ranges, the more blocks a transfer function leaves
    transparent.

    Parameters
    ----------
    data : (nx, ny, nz) array
    negmass : float
    reach : {0, 1}

    Returns
    -------
    lo, hi : (bx, by, bz) float64 with ``b = (n - 1) // BLOCK + 1`` per axis
    """
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    p = pad_linear(np.asarray(data), 1)  # sample s is p[s + 1]
    lo, hi = p, p
    for axis, n in enumerate(np.asarray(data).shape):
        # the window p[BLOCK b + 1 - reach .. BLOCK b + 1 + BLOCK + reach] of block b, centred
        # at BLOCK b + 1 + BLOCK / 2 (clipped at the end, where the box cuts the window anyway)
        centres = np.minimum(BLOCK * np.arange((n - 1) // BLOCK + 1) + 1 + BLOCK // 2,
                             p.shape[axis] - 1)
        size = BLOCK + 1 + 2 * reach
        lo = minimum_filter1d(lo, size, axis=axis, mode="nearest").take(centres, axis)
        hi = maximum_filter1d(hi, size, axis=axis, mode="nearest").take(centres, axis)
    w = negmass * (hi - lo)
    return lo - w, hi + w


#: the largest leap distance stored (uint8)
MAX_LEAP = 255


def leap_distances(transparent: np.ndarray) -> np.ndarray:
    """Per block, the Chebyshev distance to the nearest block that is not transparent.

    A value ``k >= 1`` says that the cube of ``(2k - 1)^3`` blocks centred at the block is
    transparent, so a ray in it may leap to where it leaves that cube; 0: the block itself is
    not transparent. Blocks beyond the grid count as transparent (rays end at the box).

    Parameters
    ----------
    transparent : (bx, by, bz) bool

    Returns
    -------
    (bx, by, bz) uint8, capped at :data:`MAX_LEAP`
    """
    from scipy.ndimage import distance_transform_cdt

    transparent = np.asarray(transparent, dtype=bool)
    if transparent.all():
        return np.full(transparent.shape, MAX_LEAP, np.uint8)
    dist = distance_transform_cdt(transparent, metric="chessboard")
    return np.minimum(dist, MAX_LEAP).astype(np.uint8)


class VolumeRenderer:
    """Emission-absorption rendering of a spline model of a volume.

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array
    model : str
        Spline model name.
    tf : TransferFunction
    device : str or None
        As :class:`~splineviz.compute.raycast.RayCaster`'s.
    step : float
        Sample distance along the rays in voxels of the smallest spacing.
    shaded : bool
        Headlight Phong shading from the spline's exact gradient.
    preintegrated : bool
        Composite pre-integrated segments between consecutive samples
        (:meth:`TransferFunction.preintegrated`) instead of point samples: thin opacity
        peaks between two samples are not missed.
    **model_kwargs
        Options of the model.

    Notes
    -----
    ``stats``: ``path`` (``"opencl"`` or ``"numpy"``), ``render_s``, ``skipped_blocks`` (the
    blocks the current transfer function makes transparent).
    """

    def __init__(self, volume, model: str, tf: TransferFunction, device: str | None = None,
                 step: float = 0.5, shaded: bool = True, preintegrated: bool = False,
                 **model_kwargs):
        if not isinstance(volume, Volume):
            volume = Volume(volume)
        self.caster = RayCaster(volume, model=model, device=device, **model_kwargs)
        self.model = model
        self.step = float(step)
        self.shaded = bool(shaded)
        self.preintegrated = bool(preintegrated)
        fam = self.caster.family
        self._device = self.caster._device if fam is not None and fam.name in \
            DEVICE_FAMILIES else None
        self.stats = {"path": "opencl" if self._device is not None else "numpy",
                      "render_s": None, "skipped_blocks": None}
        self._bounds = None
        if self._device is not None:
            self._bounds = block_bounds(volume.data, float(self.caster._negmass),
                                        0 if fam.name == "trilinear" else 1)
        self.set_transfer_function(tf)

    @property
    def volume(self) -> Volume:
        return self.caster.volume

    def set_transfer_function(self, tf: TransferFunction) -> None:
        """Use ``tf`` from the next frame: its table and the blocks it makes transparent
        (the per-volume block ranges are kept)."""
        self.tf = tf
        if self._device is None:
            return
        import pyopencl.array as cla

        q = self._device.queue
        empty = tf.transparent_between(*self._bounds)
        self.stats["skipped_blocks"] = int(np.count_nonzero(empty))
        self._leap = cla.to_device(q, np.ascontiguousarray(leap_distances(empty)))
        self._table = cla.to_device(q, np.ascontiguousarray(tf.table(), np.float32))
        self._pre = None

    def render(self, camera: Camera, size=(512, 512), clip_planes=(), stop=None,
               background=(0.0, 0.0, 0.0)) -> ref.DVRFrame:
        """One frame.

        Parameters
        ----------
        camera : Camera
        size : (width, height) or "WxH"
        clip_planes : sequence of (origin, normal); each keeps the side its normal points to
        stop : (t (H, W), rgba (H, W, 4), depth (H, W)), optional
            Where each ray ends (world ray parameter, inf: nowhere), the straight colour and
            opacity composited behind there and its window depth: an embedded isosurface's
            hits or opaque geometry (:func:`isosurface_stop`, :func:`depth_stop`).
        background : RGB in [0, 1]

        Returns
        -------
        DVRFrame
        """
        w, h = parse_size(size)
        vol = self.volume
        planes = volume_frame.planes_to_volume(vol, normalize_clip_planes(clip_planes))
        camera = volume_frame.camera_to_volume(vol, camera)
        t = time.perf_counter()
        if self._device is None:
            spline = self.caster.spline
            frame = ref.reference_dvr(spline.value_gradient, vol.bounds, vol.spacing, camera,
                                      (w, h), self.tf, self.step, self.shaded, planes, stop,
                                      background, preintegrated=self.preintegrated)
        else:
            frame = self._render_cl(camera, w, h, planes, stop, background)
        self.stats["render_s"] = time.perf_counter() - t
        return frame

    def _defines(self) -> dict:
        rc = self.caster
        return {**rc._defines(), "TF_SIZE": TABLE_SIZE, "BLOCK": BLOCK,
                "PREINT_SIZE": PREINT_SIZE,
                "ERT_ALPHA": ref.ERT_ALPHA, "DEPTH_ALPHA": ref.DEPTH_ALPHA}

    def _render_cl(self, camera, w, h, planes, stop, background) -> ref.DVRFrame:
        import pyopencl.array as cla
        from pyopencl import cltypes

        rc = self.caster
        q = self._device.queue
        vol = self.volume
        kernel = get_kernel(self._device.context, "dvr", "dvr", self._defines(),
                            rc._prelude() + kernel_source("raycast"))
        origin = np.asarray(vol.origin, dtype=np.float64)
        spacing = np.asarray(vol.spacing, dtype=np.float64)
        right, up, dop = camera.basis()
        tan_half = np.tan(np.radians(camera.view_angle) / 2.0)
        eye_u = (np.asarray(camera.position, dtype=np.float64) - origin) / spacing
        depth_a, depth_b = camera.projection_constants(camera.fit_clipping_range(vol.bounds))
        pl = np.zeros((max(len(planes), 1), 4), dtype=np.float32)
        for i, (po, pn) in enumerate(planes):
            pl[i, :3] = spacing * pn
            pl[i, 3] = np.dot(origin - po, pn)
        n = w * h
        if stop is None:
            stop_t = cla.to_device(q, np.full(n, np.inf, np.float32))
            stop_rgba = cla.zeros(q, (n, 4), np.float32)
            stop_depth = cla.zeros(q, n, np.float32)
        else:
            stop_t = cla.to_device(q, np.ascontiguousarray(stop[0], np.float32).ravel())
            stop_rgba = cla.to_device(q, np.ascontiguousarray(stop[1], np.float32)
                                      .reshape(n, 4))
            stop_depth = cla.to_device(q, np.ascontiguousarray(stop[2], np.float32).ravel())

        def f3(v):
            return cltypes.make_float3(*(float(x) for x in v))

        fam = rc.family
        model_args = []
        if fam.name == "type6":
            model_args = [fam._stencil.data, fam._tet_dense.data, fam._bary.data,
                          fam._red.data]
        lo, hi = self.tf.range
        unit = float(spacing.min()) * UNIT_STEP
        dt = self.step * float(spacing.min())
        if self.preintegrated and (self._pre is None or self._pre[0] != dt / unit):
            table = self.tf.preintegrated(dt / unit)
            self._pre = (dt / unit, cla.to_device(q, np.ascontiguousarray(table)))
        pre = self._pre[1] if self.preintegrated else self._table
        rgba = cla.empty(q, (n, 4), np.float32)
        depth = cla.empty(q, n, np.float32)
        color = cla.empty(q, (n, 4), np.uint8)
        nx, ny, nz = vol.shape
        bx, by, bz = self._leap.shape
        gx, gy = 8, 8
        kernel(q, (-(-w // gx) * gx, -(-h // gy) * gy), (gx, gy), rc._data.data,
               np.int32(nx), np.int32(ny), np.int32(nz),
               np.int32(rc._strides[0]), np.int32(rc._strides[1]), *model_args,
               self._leap.data, np.int32(bx), np.int32(by), np.int32(bz),
               self._table.data, np.float32(lo), np.float32((TABLE_SIZE - 1) / (hi - lo)),
               np.int32(self.preintegrated), pre.data,
               np.float32((PREINT_SIZE - 1) / (hi - lo)),
               np.float32(dt), np.float32(dt / unit), np.int32(self.shaded),
               f3(eye_u), f3(dop), f3(right * tan_half * w / h), f3(up * tan_half),
               f3(1.0 / spacing), cla.to_device(q, pl).data, np.int32(len(planes)),
               np.float32(depth_a), np.float32(depth_b), stop_t.data, stop_rgba.data,
               stop_depth.data, f3(background), rgba.data, depth.data, color.data,
               np.int32(w), np.int32(h))
        return ref.DVRFrame(rgba.get(queue=q).reshape(h, w, 4),
                            depth.get(queue=q).reshape(h, w),
                            color.get(queue=q).reshape(h, w, 4))


def isosurface_stop(frame, camera: Camera):
    """The stop of :meth:`VolumeRenderer.render` from an isosurface frame of the same camera
    and size (``RayCaster.render``): rays end at the exact hits, the shaded surface colour
    (opaque) behind, its depth.

    Returns
    -------
    (t (H, W) float64, rgba (H, W, 4) float32, depth (H, W) float32)
    """
    origin, _ = camera.rays(frame.hit.shape[::-1])
    pos = frame.position
    t = np.where(frame.hit, np.linalg.norm(np.nan_to_num(pos) - origin, axis=-1), np.inf)
    rgba = frame.color.astype(np.float32) / 255.0
    rgba[..., 3] = frame.hit
    return t, rgba, frame.depth


def depth_stop(depth, color, camera: Camera, clipping_range):
    """The stop of :meth:`VolumeRenderer.render` from an opaque geometry's window depth and
    colour (e.g. a mesh's render target): rays end where their depth reaches it.

    Parameters
    ----------
    depth : (H, W) window depth (1: nothing)
    color : (H, W, 3 or 4) uint8
    camera : Camera
    clipping_range : (near, far) of ``depth`` (the volume renderer's own range)

    Returns
    -------
    (t (H, W), rgba (H, W, 4) float32, depth (H, W) float32)
    """
    near, far = clipping_range
    h, w = depth.shape
    _, dirs = camera.rays((w, h))
    dz = dirs @ camera.basis()[2]
    d = np.asarray(depth, np.float64)
    a, b = camera.projection_constants((near, far))
    with np.errstate(divide="ignore"):
        ze = b / (a - d)
    t = np.where(d < 1.0, ze / dz, np.inf)
    rgba = np.zeros((h, w, 4), np.float32)
    rgba[..., :3] = np.asarray(color)[..., :3] / 255.0
    rgba[..., 3] = d < 1.0
    return t, rgba, np.asarray(depth, np.float32)
