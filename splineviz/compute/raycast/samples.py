"""Device samples of the ray caster: their type, ghost layers, and the trilinear cell bounds
of the NumPy path."""

from __future__ import annotations

import numpy as np

from splineviz.core.volume import slabs

#: device sample types tried in order (numpy type, OpenCL C type) for integer-valued data
SAMPLE_TYPES = ((np.uint8, "uchar"), (np.int16, "short"), (np.uint16, "ushort"))


def sample_type_for(data: np.ndarray, ghost: int) -> tuple[type, str]:
    """The device type of the samples: the smallest integer type that holds them exactly with
    ``ghost`` linearly extrapolated layers (integer samples, as :class:`Volume` keeps them,
    or float samples of integer values: 4x/2x less device memory and bandwidth than
    float32), else float32.

    Parameters
    ----------
    data : (nx, ny, nz) array, any real type
    ghost : ghost layers (each axis' extrapolation widens the value range by ``2 ghost``
        times its width, and integers stay integers)

    Returns
    -------
    (numpy type, OpenCL C type name)
    """
    integers = data.dtype.kind in "biu"
    lo, hi = np.inf, -np.inf
    for s in slabs(data):  # about 16 M samples at a time: no big temporaries
        if not integers and not np.array_equal(s, np.rint(s)):  # fractions, NaN or inf
            return np.float32, "float"
        lo, hi = min(lo, float(s.min())), max(hi, float(s.max()))
    grow = (hi - lo) * ghost * sum((1 + 2 * ghost) ** a for a in range(3))
    for np_type, cl_type in SAMPLE_TYPES:
        info = np.iinfo(np_type)
        if info.min <= lo - grow and hi + grow <= info.max:
            return np_type, cl_type
    return np.float32, "float"


def pad_linear_into(data: np.ndarray, layers: int, out: np.ndarray) -> None:
    """:func:`splineviz.core.splines.boundary.pad_linear` written into a smaller array type.

    The ghost samples are computed one slab at a time in float64 (as the core does, up to a
    rounding of the ghosts of earlier axes), so no float64 copy of the volume is made.

    Parameters
    ----------
    data : (nx, ny, nz) array
    layers : int >= 1
    out : (nx + 2 layers, ny + 2 layers, nz + 2 layers), written; float32, or an integer
        type that holds the padded values exactly (:func:`sample_type_for`)
    """
    g = layers
    n = data.shape
    out[g:g + n[0], g:g + n[1], g:g + n[2]] = data
    for axis in range(3):
        # as the core: axes before `axis` are already padded, the later ones not yet
        region = [slice(None) if ax < axis else slice(g, g + n[ax]) for ax in range(3)]

        def at(i, region=region, axis=axis):
            r = list(region)
            r[axis] = i
            return tuple(r)

        lo = out[at(g)].astype(np.float64), out[at(g + min(1, n[axis] - 1))].astype(np.float64)
        hi = (out[at(g + n[axis] - 1)].astype(np.float64),
              out[at(g + max(n[axis] - 2, 0))].astype(np.float64))
        for m in range(1, g + 1):
            # a single sample is repeated (its "neighbour" is itself, so the slope is 0)
            out[at(g - m)] = (1 + m) * lo[0] - m * lo[1]
            out[at(g + n[axis] - 1 + m)] = (1 + m) * hi[0] - m * hi[1]


def numpy_cell_bounds(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-cell (min, max) of the 8 corner samples: the trilinear model's value bounds.

    Parameters
    ----------
    data : (nx, ny, nz) array, any real type

    Returns
    -------
    vmin, vmax : (nx-1, ny-1, nz-1) float32
    """
    # in the samples' own type (min and max commute with the exact conversion to float32)
    d = np.asarray(data)
    corners = [d[i:d.shape[0] - 1 + i, j:d.shape[1] - 1 + j, k:d.shape[2] - 1 + k]
               for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    return (np.minimum.reduce(corners).astype(np.float32, copy=False),
            np.maximum.reduce(corners).astype(np.float32, copy=False))



def padded_device_samples(device, data: np.ndarray, ghost: int, dtype, out=None):
    """The samples with ``ghost`` linearly extrapolated layers in their device type, written
    straight into a device buffer (no host copy of the padded volume).

    Parameters
    ----------
    device : splineviz.compute.device.Device
    data : (nx, ny, nz) array in the volume's type (integers are written as they are)
    ghost : int
    dtype : numpy type of the device samples (:func:`sample_type_for`)
    out : pyopencl.array.Array, optional
        A buffer of these padded samples' shape and type to write into (a new step of a
        time series), instead of a new one.

    Returns
    -------
    pyopencl.array.Array of shape (nx + 2 ghost, ny + 2 ghost, nz + 2 ghost)
    """
    import pyopencl as cl
    import pyopencl.array as cla

    q = device.queue
    shape = tuple(n + 2 * ghost for n in data.shape)
    dtype = np.dtype(dtype)
    if out is not None and (out.shape != shape or out.dtype != dtype):
        raise AssertionError("the device samples changed shape or type")  # a bug of the caller
    if out is None:
        mf = cl.mem_flags
        buf = cl.Buffer(device.context, mf.READ_ONLY | mf.ALLOC_HOST_PTR,
                        dtype.itemsize * int(np.prod(shape)))
        out = cla.Array(q, shape, dtype, data=buf)
    # the map waits for the kernels still reading the old samples (one in-order queue)
    host, _ = cl.enqueue_map_buffer(q, out.data, cl.map_flags.WRITE_INVALIDATE_REGION, 0,
                                    shape, dtype)
    pad_linear_into(data, ghost, host)
    host.base.release(q)
    return out


def sample_blocks(rc) -> list:
    """Enqueue classify.cl's ``sample_blocks`` on ``rc``'s device samples: the (min, max) of
    their 2 x 2 x 2 blocks, in the samples' type (a quarter of their bytes), which the
    octree's level-1 pass of the type-6 and TO families reads instead of the samples.

    Returns
    -------
    list
        The kernel arguments ``blocks`` ((bx, by, bz, 2) buffer), ``bx``, ``by``, ``bz``
        (blocks per axis: half the padded samples, rounded up). OpenCL frees the buffer once
        the kernels enqueued with it are done.
    """
    import pyopencl.array as cla

    from splineviz.compute.program import get_kernel

    q = rc._device.queue
    px, py, pz = rc._data.shape
    nb = tuple((n + 1) // 2 for n in (px, py, pz))
    blocks = cla.empty(q, (*nb, 2), rc._sample_type[0])
    get_kernel(rc._device.context, "classify", "sample_blocks", rc._cls_defines)(
        q, nb[::-1], None, rc._data.data, np.int32(px), np.int32(py), np.int32(pz),
        blocks.data)
    return [blocks.data, *(np.int32(n) for n in nb)]
