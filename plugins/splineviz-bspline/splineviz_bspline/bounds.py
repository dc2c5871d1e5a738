"""Value bounds of the tricubic B-spline on each unit cell, from its Bernstein (Bezier) form.

On a cell the spline is a tensor-product cubic whose 4 x 4 x 4 Bernstein coefficients are
convex combinations of the cell's B-spline coefficients (per axis the matrix
:data:`BSPLINE_TO_BERNSTEIN`); the spline on the cell lies within their range. That range is
much tighter than the B-spline coefficients' own: the interpolation prefilter makes the
coefficients of noisy data overshoot the data, so nearly every cell near a surface straddles
the isovalue by its coefficients, and only a few by its Bernstein coefficients.

The device computes them (``bounds.cl``: :func:`device_cell_bounds`, :func:`device_octree`);
:func:`cell_bounds` and :func:`octree_bounds` are the NumPy reference they are tested against.
"""

from __future__ import annotations

import numpy as np

from splineviz.compute.raycast.octree import octree_nodes

#: Bernstein coefficients on [0, 1] (rows) of the uniform cubic B-spline weights of the
#: coefficient offsets -1, 0, 1, 2 (columns); every row is >= 0 and sums to 1
BSPLINE_TO_BERNSTEIN = np.array([[1.0, 4.0, 1.0, 0.0],
                                 [0.0, 4.0, 2.0, 0.0],
                                 [0.0, 2.0, 4.0, 0.0],
                                 [0.0, 1.0, 4.0, 1.0]]) / 6.0

#: widening of the cell bounds, relative to the largest coefficient the cell reads: covers
#: the float32 rounding of the conversion and of the ray kernel's restriction (sums of a few
#: dozen products, a few ulps each), so that a cell rejected by its bounds is one whose
#: computed polynomial keeps one sign too
SLACK = 1e-5

_programs: dict = {}
_kernels: dict = {}


def _to_bernstein(c: np.ndarray, axis: int) -> list[np.ndarray]:
    """The 4 Bernstein coefficient arrays along ``axis`` of the cells of ``c`` (n - 3 along
    that axis: cell i reads c[i .. i + 3])."""
    n = c.shape[axis] - 3
    parts = [np.take(c, np.arange(a, a + n), axis=axis) for a in range(4)]
    return [sum(m[a] * parts[a] for a in range(4) if m[a] != 0.0)
            for m in BSPLINE_TO_BERNSTEIN]


def cell_bounds(coefficients: np.ndarray) -> np.ndarray:
    """Lower and upper bounds of the spline on every cell (NumPy reference, not widened).

    Parameters
    ----------
    coefficients : (nx + 3, ny + 3, nz + 3) float
        B-spline coefficients; cell (i, j, k) reads coefficients i..i+3, j..j+3, k..k+3.

    Returns
    -------
    (nx, ny, nz, 2) float64: the min and max of each cell's Bernstein coefficients (NaN where
    a coefficient the cell reads is NaN).
    """
    c = np.asarray(coefficients, dtype=np.float64)
    lo = hi = None
    for bx in _to_bernstein(c, 0):
        for by in _to_bernstein(bx, 1):
            for bz in _to_bernstein(by, 2):
                # np.fmin would drop NaN: a cell with a NaN coefficient stays unbounded
                lo = bz if lo is None else np.minimum(lo, bz)
                hi = bz if hi is None else np.maximum(hi, bz)
    return np.stack([lo, hi], axis=-1)


def _reduce(nodes: np.ndarray) -> np.ndarray:
    """(lo, hi) of the 2 x 2 x 2 blocks of ``nodes`` (n, m, p, 2), NaN ignored."""
    nx, ny, nz = ((n + 1) // 2 for n in nodes.shape[:3])
    lo = np.full((2 * nx, 2 * ny, 2 * nz), np.inf, dtype=nodes.dtype)
    hi = np.full((2 * nx, 2 * ny, 2 * nz), -np.inf, dtype=nodes.dtype)
    n, m, p = nodes.shape[:3]
    lo[:n, :m, :p] = np.where(np.isnan(nodes[..., 0]), np.inf, nodes[..., 0])
    hi[:n, :m, :p] = np.where(np.isnan(nodes[..., 1]), -np.inf, nodes[..., 1])
    lo = lo.reshape(nx, 2, ny, 2, nz, 2).min(axis=(1, 3, 5))
    hi = hi.reshape(nx, 2, ny, 2, nz, 2).max(axis=(1, 3, 5))
    return np.stack([lo, hi], axis=-1)


def octree_bounds(level1: np.ndarray, levels) -> np.ndarray:
    """All stored levels of the min-max octree from its first.

    Parameters
    ----------
    level1 : (dx, dy, dz, 2) float32
        (lo, hi) of the nodes of 2 x 2 x 2 cells (:func:`node_bounds`).
    levels : list of (offset, nx, ny, nz)
        :func:`splineviz.compute.raycast.octree.octree_levels` of the cells.

    Returns
    -------
    (nodes, 2) float32: (lo, hi) of every node, level after level, as classify.cl lays them
    out.
    """
    out = np.empty((octree_nodes(levels), 2), dtype=np.float32)
    cur = level1
    for i, (off, nx, ny, nz) in enumerate(levels):
        if i:
            cur = _reduce(cur)
        out[off:off + nx * ny * nz] = cur.reshape(-1, 2)
    return out


def node_bounds(cells: np.ndarray) -> np.ndarray:
    """(dx, dy, dz, 2) bounds of the octree's nodes of 2 x 2 x 2 of the (cx, cy, cz, 2)
    ``cells`` (NumPy reference of ``bspline_node_bounds``; NaN ignored as classify.cl does)."""
    return _reduce(cells)


def _kernel(context, name: str):
    """Kernel ``name`` of ``bounds.cl`` for ``context``, built once (a kernel object too:
    pyopencl makes a new one at every attribute access)."""
    from importlib import resources

    import pyopencl as cl

    kernel = _kernels.get((context.int_ptr, name))
    if kernel is None:
        program = _programs.get(context.int_ptr)
        if program is None:
            source = resources.files("splineviz_bspline").joinpath("bounds.cl").read_text()
            program = _programs[context.int_ptr] = cl.Program(context, source).build()
        kernel = _kernels[context.int_ptr, name] = cl.Kernel(program, name)
    return kernel


def device_cell_bounds(queue, samples, shape: tuple[int, int, int]):
    """Widened float32 (lo, hi) of every cell on the device.

    Parameters
    ----------
    queue : pyopencl.CommandQueue
    samples : pyopencl.array.Array
        The (sx, sy, sz) = ``shape`` float32 coefficients, flat or not.

    Returns
    -------
    pyopencl.array.Array of 2 sx sy sz float32: entries 2 s, 2 s + 1 (s the flat index of
    sample (i, j, k)) bound the cell whose first coefficient is (i, j, k), widened by
    :data:`SLACK`; (-inf, inf) where no cell starts, NaN for a cell that reads a NaN.
    """
    import pyopencl.array as cla

    sx, sy, sz = shape
    table = cla.empty(queue, 2 * sx * sy * sz, np.float32)
    _kernel(queue.context, "bspline_cell_bounds")(
        queue, (sz, sy, sx), None, samples.data, np.int32(sx), np.int32(sy), np.int32(sz),
        np.float32(SLACK), table.data)
    return table


def device_octree(queue, table, shape: tuple[int, int, int], levels, bounds) -> None:
    """Write the min-max octree of the cell bounds ``table`` (:func:`device_cell_bounds` of
    samples of ``shape``) into ``bounds``, the ray caster's (2 nodes,) float32 array laid
    out by ``levels``."""
    sx, sy, sz = shape
    _, dx, dy, dz = levels[0]
    _kernel(queue.context, "bspline_node_bounds")(
        queue, (dz, dy, dx), None, table.data, np.int32(sy), np.int32(sz),
        np.int32(sx - 3), np.int32(sy - 3), np.int32(sz - 3), bounds.data)
    level1 = bounds[:2 * dx * dy * dz].get().reshape(dx, dy, dz, 2)
    bounds.set(octree_bounds(level1, levels).ravel())
