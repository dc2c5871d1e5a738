"""The cell bounds of the "tricubic-bspline" plugin's kernel family (its Bernstein form) and
the min-max octree it builds from them."""

import numpy as np
import pytest

import splineviz as sv
from splineviz import plugins

from .helpers import HAVE_CL

pytestmark = pytest.mark.skipif(
    "bspline" not in {r.name for r in plugins.discover()},
    reason="plugins/splineviz-bspline is not installed (./install.sh --dev)")

RNG = np.random.default_rng(23)


def _spline_at(c, cell, t):
    """The spline of coefficients ``c`` at local coordinates t (N, 3) of ``cell``."""
    from splineviz_bspline.model import bspline_weights

    w = [bspline_weights(t[:, a])[0] for a in range(3)]  # (N, 4) each
    i, j, k = cell
    block = c[i:i + 4, j:j + 4, k:k + 4]
    return np.einsum("na,nb,nc,abc->n", w[0], w[1], w[2], block)


def test_the_bernstein_matrix_gives_the_b_spline_weights():
    from math import comb

    from splineviz_bspline.bounds import BSPLINE_TO_BERNSTEIN
    from splineviz_bspline.model import bspline_weights

    t = np.linspace(0.0, 1.0, 11)
    bern = np.stack([comb(3, j) * t**j * (1 - t) ** (3 - j) for j in range(4)], axis=1)
    np.testing.assert_allclose(bern @ BSPLINE_TO_BERNSTEIN, bspline_weights(t)[0],
                               atol=1e-15)
    assert (BSPLINE_TO_BERNSTEIN >= 0).all()
    np.testing.assert_allclose(BSPLINE_TO_BERNSTEIN.sum(axis=1), 1.0)


def test_cell_bounds_hold_the_spline_and_are_its_corner_values_at_the_extremes():
    from splineviz_bspline.bounds import cell_bounds

    # more cells along x than one slab of the conversion
    c = RNG.normal(size=(40, 6, 7)) ** 3
    bounds = cell_bounds(c)
    assert bounds.shape == (37, 3, 4, 2)
    for cell in [(0, 0, 0), (36, 2, 3), (31, 1, 2), (32, 0, 1), (17, 2, 0)]:
        s = _spline_at(c, cell, RNG.uniform(size=(400, 3)))
        lo, hi = bounds[cell]
        assert lo - 1e-12 <= s.min() and s.max() <= hi + 1e-12
        # the corner values are Bernstein coefficients: the bounds are no wider than them
        corners = _spline_at(c, cell, np.array(np.meshgrid(*[[0.0, 1.0]] * 3)).reshape(3, -1).T)
        assert lo <= corners.min() + 1e-12 and corners.max() <= hi + 1e-12
        # and tighter than the B-spline coefficients' range
        block = c[cell[0]:cell[0] + 4, cell[1]:cell[1] + 4, cell[2]:cell[2] + 4]
        assert block.min() <= lo and hi <= block.max()


def test_a_nan_coefficient_leaves_its_cells_unbounded():
    from splineviz_bspline.bounds import cell_bounds

    c = RNG.normal(size=(8, 8, 8))
    c[2, 2, 2] = np.nan
    bounds = cell_bounds(c)
    # cells 0..2 per axis read coefficient 2, cells 3 and 4 do not
    assert np.isnan(bounds[:3, :3, :3]).all()
    assert np.isfinite(bounds[3:, :, :]).all() and np.isfinite(bounds[:, :, 3:]).all()


def test_the_octree_holds_the_bounds_of_its_cells():
    from splineviz_bspline.bounds import node_bounds, octree_bounds

    from splineviz.compute.raycast.octree import octree_levels

    cells = RNG.normal(size=(5, 6, 3, 2)).astype(np.float32)
    cells.sort(axis=-1)
    cells[4, 5, 2] = np.nan  # ignored, as classify.cl's min/max ignore NaN
    levels = octree_levels(cells.shape[:3])
    tree = octree_bounds(node_bounds(cells), levels)
    for level, (off, nx, ny, nz) in enumerate(levels, start=1):
        span = 2**level
        for a, b, c in [(0, 0, 0), (nx - 1, ny - 1, nz - 1), (nx // 2, 0, nz - 1)]:
            block = cells[a * span:(a + 1) * span, b * span:(b + 1) * span,
                          c * span:(c + 1) * span]
            lo, hi = tree[off + (a * ny + b) * nz + c]
            assert lo == np.nanmin(block[..., 0]) and hi == np.nanmax(block[..., 1])


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
def test_the_device_bounds_and_octree_are_the_numpy_ones():
    from splineviz_bspline.bounds import (
        SLACK,
        cell_bounds,
        device_cell_bounds,
        node_bounds,
        octree_bounds,
    )

    plugins.ensure_loaded()
    data = RNG.normal(size=(9, 7, 8))
    rc = sv.RayCaster(sv.Volume(data), model="tricubic-bspline", device="cpu")
    samples = rc.family.device_samples(rc)
    table = device_cell_bounds(rc._device.queue, rc._data, samples.shape).get()
    table = table.reshape(*samples.shape, 2)
    cells = table[:-3, :-3, :-3]
    width = cells - cell_bounds(samples)
    # widened by SLACK times the cell's largest coefficient, up to float32 rounding
    assert (width[..., 0] <= 0).all() and (width[..., 1] >= 0).all()
    assert np.abs(width).max() <= 1.1 * SLACK * np.abs(samples).max()
    assert np.isneginf(table[-3:, ..., 0]).all() and np.isposinf(table[:, -3:, :, 1]).all()
    # the ray caster's octree is that of the Bernstein bounds, not classify.cl's
    tree = rc._bounds.get().reshape(-1, 2)
    np.testing.assert_array_equal(tree, octree_bounds(node_bounds(cells), rc._levels))
