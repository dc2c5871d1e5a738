"""The OpenCL kernel family of the tricubic B-spline: ``bspline.cl`` beside this module.

Its device samples are the spline's coefficients with one mirrored layer (float32), so that a
unit cell reads the 4 x 4 x 4 coefficients of its pieces without a boundary test; the
kernel restricts the spline to the ray in a cell exactly (a polynomial of degree <= 9 in
Bernstein form) and isolates its first root by subdivision (see ``bspline.cl``).

Each cell's value bounds come from its Bernstein form
(:func:`splineviz_bspline.bounds.cell_bounds`) rather than from the B-spline coefficients,
which the prefilter makes overshoot the data: on CT data nearly every cell a ray crosses near
the surface straddles the isovalue by its coefficients, ~1 in 12 by its Bernstein
coefficients. They replace the levels of the ray caster's min-max octree (so that empty-space
leaping skips what they exclude), and the same device buffer holds them after the samples,
indexed like the cell's first sample, for the kernel's test of a single cell (two loads
instead of 64).
"""

from __future__ import annotations

import numpy as np

from splineviz.compute.raycast import CustomKernelFamily
from splineviz.compute.raycast.octree import octree_nodes
from splineviz_bspline.bounds import cell_bounds

#: widening of the cell bounds, relative to the largest coefficient the cell reads: covers
#: the float32 rounding of the kernel's restriction (sums of 64 products, a few ulps each),
#: so that a cell it rejects is one whose computed polynomial keeps one sign too
BOUNDS_SLACK = 1e-5


def _window_max(a: np.ndarray) -> np.ndarray:
    """(nx - 3, ny - 3, nz - 3) maxima of ``a`` over the 4 x 4 x 4 windows a cell reads."""
    from numpy.lib.stride_tricks import sliding_window_view

    for axis in range(3):
        a = sliding_window_view(a, 4, axis=axis).max(axis=-1)
    return a


def octree_bounds(cells: np.ndarray, levels) -> np.ndarray:
    """The stored levels of the min-max octree from per-cell bounds.

    Parameters
    ----------
    cells : (cx, cy, cz, 2) float32
        (lo, hi) of every cell.
    levels : list of (offset, nx, ny, nz)
        :func:`splineviz.compute.raycast.octree.octree_levels` of (cx, cy, cz).

    Returns
    -------
    (nodes, 2) float32: (lo, hi) of every node, level after level, as classify.cl lays them
    out; NaN bounds are ignored as its min/max ignore them.
    """
    out = np.empty((octree_nodes(levels), 2), dtype=np.float32)
    cur = cells
    for off, nx, ny, nz in levels:
        pad = np.full((2 * nx, 2 * ny, 2 * nz, 2), np.nan, dtype=np.float32)
        pad[:cur.shape[0], :cur.shape[1], :cur.shape[2]] = cur
        blocks = pad.reshape(nx, 2, ny, 2, nz, 2, 2)
        lo = np.fmin.reduce(blocks[..., 0], axis=(1, 3, 5))
        hi = np.fmax.reduce(blocks[..., 1], axis=(1, 3, 5))
        cur = np.stack([lo, hi], axis=-1)
        out[off:off + nx * ny * nz] = cur.reshape(-1, 2)
    return out


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

    def device_cell_bounds(self, samples: np.ndarray) -> np.ndarray:
        """Widened float32 (lo, hi) of every cell, shape ``samples.shape + (2,)``: entry
        (i, j, k) bounds the cell whose first sample is (i, j, k); entries of no cell are
        (-inf, inf)."""
        coefficients = samples.astype(np.float64)
        bounds = cell_bounds(coefficients)
        slack = BOUNDS_SLACK * _window_max(np.abs(coefficients))
        table = np.empty(samples.shape + (2,), dtype=np.float32)
        table[..., 0] = -np.inf
        table[..., 1] = np.inf
        nx, ny, nz = bounds.shape[:3]
        table[:nx, :ny, :nz, 0] = bounds[..., 0] - slack
        table[:nx, :ny, :nz, 1] = bounds[..., 1] + slack
        return table

    def upload(self, rc) -> dict:
        import pyopencl.array as cla

        tables = super().upload(rc)
        samples = rc._data.get()
        table = self.device_cell_bounds(samples)
        if samples.nbytes + table.nbytes <= rc._device.device.max_mem_alloc_size:
            rc._data = cla.to_device(rc._device.queue,
                                     np.concatenate([samples.ravel(), table.ravel()]))
            self._bounds_at = samples.size
        else:
            self._bounds_at = None
        self._cells = table[:-3, :-3, :-3]
        return tables

    def allocate(self, rc) -> None:
        """The octree of the Bernstein bounds in place of classify.cl's (built by then)."""
        rc._bounds.set(octree_bounds(self._cells, rc._levels).ravel())
        self._cells = None

    def defines(self, rc) -> dict:
        out = super().defines(rc)
        if getattr(self, "_bounds_at", None) is not None:
            out["BS_BOUNDS"] = self._bounds_at
        return out
