"""The OpenCL kernel family of the tricubic B-spline: ``bspline.cl`` beside this module.

Its device samples are the spline's coefficients with one mirrored layer (float32), so that a
unit cell reads the 4 x 4 x 4 coefficients of its pieces without a boundary test; the
kernel restricts the spline to the ray in a cell exactly (a polynomial of degree <= 9 in
Bernstein form) and isolates its first root by subdivision (see ``bspline.cl``).

The ray caster's min-max octree bounds the cells by the range of their Bernstein
coefficients (:mod:`splineviz_bspline.bounds`, computed on the device) rather than of their
B-spline coefficients, which the prefilter makes overshoot the data: on CT data nearly every
cell a ray crosses near the surface straddles the isovalue by its coefficients, ~1 in 12 by
its Bernstein coefficients, and empty-space leaping skips the rest.
"""

from __future__ import annotations

import numpy as np

from splineviz.compute.raycast import CustomKernelFamily
from splineviz_bspline.bounds import device_cell_bounds, device_octree


class TricubicBSplineFamily(CustomKernelFamily):
    """Ray casting of ``"tricubic-bspline"`` on the OpenCL device."""

    name = "tricubic-bspline"
    source = ("splineviz_bspline", "bspline.cl")
    ghost_layers = 1
    #: cell (i, j, k) reads the coefficients i-1..i+2 per axis: device samples i..i+3
    reach = 3
    #: the B-spline weights are >= 0 and sum to 1: the coefficients bound the spline
    negmass = 0.0
    #: the prefilter reads the whole volume: a brick's samples give another spline
    bricks = False

    def device_samples(self, rc) -> np.ndarray:
        """(nx + 2, ny + 2, nz + 2) float32 coefficients, mirrored once at every face (as
        :func:`splineviz_bspline.model.mirror_index` extends them)."""
        coefficients = rc.spline.coefficients
        return np.pad(coefficients, 1, mode="reflect").astype(np.float32)

    def upload(self, rc) -> dict:
        """The samples, and the cells' Bernstein bounds for :meth:`allocate`."""
        tables = super().upload(rc)
        self._shape = tuple(n + 2 * self.ghost_layers for n in rc.volume.shape)
        self._table = device_cell_bounds(rc._device.queue, rc._data, self._shape)
        return tables

    def allocate(self, rc) -> None:
        """The octree of the cells' Bernstein bounds in place of classify.cl's (built from
        the coefficients by then)."""
        device_octree(rc._device.queue, self._table, self._shape, rc._levels, rc._bounds)
        self._table = None
