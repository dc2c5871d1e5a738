"""The trilinear kernel family: cells between samples; the restriction to the ray in a cell
is an exact cubic, split at its critical points so that no root is missed."""

from __future__ import annotations

import numpy as np

from splineviz.compute.raycast.family import KernelFamily, register_kernel_family
from splineviz.compute.raycast.samples import numpy_cell_bounds


@register_kernel_family
class TrilinearFamily(KernelFamily):
    """The ``"trilinear"`` model (value bounds of a cell: its 8 corners, exact)."""

    name = "trilinear"
    define = "MODEL_TRILINEAR"
    counts_tets = False

    def upload(self, rc) -> dict:
        import pyopencl.array as cla

        samples = rc.volume.data.astype(rc._sample_type[0], copy=False)
        rc._data = cla.to_device(rc._device.queue, samples)
        rc._strides = rc.volume.shape[1:]
        rc._negmass = 0.0
        return {}

    def upload_samples(self, rc) -> None:
        rc._data.set(np.ascontiguousarray(rc.volume.data, dtype=rc._sample_type[0]),
                     queue=rc._device.queue)

    def numpy_candidates(self, volume, iso: float) -> int:
        vmin, vmax = numpy_cell_bounds(volume.data)
        iso = np.float32(iso)
        return int(np.count_nonzero((vmin <= iso) & (iso <= vmax)))
