"""Gaussian smoothing of volumes on the OpenCL device (separable kernel, sigma in voxels).

Noisy data (CT, MRI) gives bumpy isosurfaces; smoothing the samples before the spline is
fitted is the usual remedy (thesis §6.3 shows smoothed data sets). The filter is the same as
``scipy.ndimage.gaussian_filter(data, sigma, mode="reflect", truncate=4.0)``: three 1-D
passes with normalised sampled Gaussian weights of radius ``int(truncate * sigma + 0.5)``;
that function is the NumPy reference (and the fallback without an OpenCL device).
"""

from __future__ import annotations

import numpy as np

from splineviz.compute.device import try_get_device
from splineviz.compute.program import get_kernel
from splineviz.core.errors import SplinevizError
from splineviz.core.volume import Volume

#: Gaussian support in standard deviations (scipy's default)
TRUNCATE = 4.0
#: largest sigma (voxels) accepted: beyond it the volume is a blur of its mean
MAX_SIGMA = 64.0


class SmoothingError(SplinevizError, ValueError):
    """Bad smoothing parameters (sigma negative, too large or not finite)."""


def gaussian_weights(sigma: float, truncate: float = TRUNCATE) -> np.ndarray:
    """Normalised weights ``exp(-t^2 / (2 sigma^2))``, ``t = -R..R``, ``R = int(truncate sigma
    + 0.5)`` (as scipy.ndimage). Returns ``(2R+1,)`` float64."""
    radius = int(truncate * float(sigma) + 0.5)
    t = np.arange(-radius, radius + 1, dtype=np.float64)
    w = np.exp(-0.5 * (t / sigma) ** 2)
    return w / w.sum()


def _sigmas(sigma) -> tuple[float, float, float]:
    s = tuple(float(v) for v in np.broadcast_to(np.asarray(sigma, dtype=np.float64), 3))
    if not all(np.isfinite(v) and 0.0 <= v <= MAX_SIGMA for v in s):
        raise SmoothingError(f"sigma must be between 0 and {MAX_SIGMA:g} voxels, got {sigma}")
    return s


def gaussian_smooth(volume: Volume, sigma, device: str | None = None) -> Volume:
    """The volume convolved with a Gaussian of ``sigma`` voxels per axis.

    Parameters
    ----------
    volume : Volume
    sigma : float or (3,) float
        Standard deviation in voxels (0 leaves an axis unchanged).
    device : str or None
        OpenCL device preference (see :func:`splineviz.compute.device.get_device`);
        ``"numpy"`` uses scipy.

    Returns
    -------
    Volume with the same spacing and origin, float32 samples.

    Examples
    --------
    >>> import numpy as np, splineviz as sv
    >>> v = sv.Volume(np.pad(np.ones((1, 1, 1)), 3))
    >>> s = gaussian_smooth(v, 1.0, device="numpy")
    >>> round(float(s.data.sum()), 4)
    1.0
    """
    sigmas = _sigmas(sigma)
    data = volume.data
    dev = try_get_device(device) if device != "numpy" else None
    if dev is None:
        from scipy.ndimage import gaussian_filter

        out = gaussian_filter(data.astype(np.float64), sigmas, mode="reflect", truncate=TRUNCATE)
    else:
        out = _smooth_cl(dev, data, sigmas)
    return Volume(out, spacing=volume.spacing, origin=volume.origin,
                  direction=getattr(volume, "direction", None), unit=volume.unit)


def _smooth_cl(dev, data: np.ndarray, sigmas) -> np.ndarray:
    import pyopencl as cl
    import pyopencl.array as cla

    q = dev.queue
    knl = get_kernel(dev.context, "smooth", "convolve_axis")
    nx, ny, nz = data.shape
    a = cla.to_device(q, np.ascontiguousarray(data, dtype=np.float32))
    b = cla.empty_like(a)
    for axis, s in enumerate(sigmas):
        if s == 0.0:
            continue
        w = gaussian_weights(s).astype(np.float32)
        radius = (len(w) - 1) // 2
        wbuf = cl.Buffer(dev.context, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                         hostbuf=w)
        knl(q, (nz, ny, nx), None, a.data, b.data, wbuf, np.int32(radius), np.int32(axis),
            np.int32(nx), np.int32(ny), np.int32(nz))
        a, b = b, a
    return a.get(queue=q)
