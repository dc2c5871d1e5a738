"""The coarse level a chunked volume previews from (issue 26, item 5): the pyramid level within
the budget, else a strided downsample read once; in memory, spanning the same world box."""

import dask.array as da
import numpy as np
import pytest

from splineviz.core.chunked import PREVIEW_SAMPLES, ChunkedVolume, Level, strided_level


def _field(shape) -> np.ndarray:
    i, j, k = np.meshgrid(*(np.arange(n, dtype=np.float32) for n in shape), indexing="ij")
    return (i + 10 * j + 100 * k).astype(np.float32)


def test_the_finest_pyramid_level_within_the_budget_is_chosen_and_named():
    full = da.zeros((256, 256, 256), chunks=64, dtype=np.uint8)
    levels = [Level(da.zeros((n,) * 3, chunks=64, dtype=np.uint8), (256 / n,) * 3,
                    (0.0, 0.0, 0.0)) for n in (128, 64)]
    vol = ChunkedVolume(full, levels=levels)
    level = vol.preview_level()
    assert level.shape == (128, 128, 128) and 128**3 <= PREVIEW_SAMPLES
    assert level.label == "coarse level 1 of 2 (128^3 of 256^3)"
    assert vol.preview_level(64**3).label == "coarse level 2 of 2 (64^3 of 256^3)"
    # every level too big: the coarsest one, downsampled
    big = ChunkedVolume(full, levels=[Level(da.zeros((160,) * 3, chunks=64, dtype=np.uint8),
                                            (1.6,) * 3, (0.0,) * 3)])
    assert big.preview_level().label == "coarse level 1 of 1 downsampled 1:2 (80^3 of 256^3)"
    assert big.preview_level().spacing == (3.2,) * 3
    small = ChunkedVolume(da.zeros((40, 30, 20), chunks=10))
    assert small.preview_level().label == "full level (40x30x20)"


def test_without_a_pyramid_every_fth_sample_is_read_once():
    data = _field((70, 64, 33))
    reads = []

    def counted(block):
        reads.append(block.shape)
        return block

    vol = ChunkedVolume(da.from_array(data, chunks=16).map_blocks(counted),
                        spacing=(0.5, 1.0, 2.0), origin=(1.0, 2.0, 3.0))
    level = vol.preview_level(20**3)
    # the smallest whole stride within the budget: 3 leaves 24 x 22 x 11 samples (2: 35 x 32
    # x 17, too many)
    assert level.shape == (24, 22, 11) and level.label == "downsample 1:3 (24x22x11 of 70x64x33)"
    assert level.spacing == (1.5, 3.0, 6.0) and level.origin == (1.0, 2.0, 3.0)
    np.testing.assert_array_equal(level.read_all(), data[::3, ::3, ::3])
    n = len(reads)
    assert vol.preview_level(20**3) is level and len(reads) == n  # kept, not read again
    # in memory, the same world box as the full data
    prev = vol.preview_volume(20**3)
    np.testing.assert_array_equal(prev.data, data[::3, ::3, ::3])
    np.testing.assert_allclose(prev.bounds, vol.bounds)
    assert vol.preview_volume(20**3) is prev and len(reads) == n


def test_a_thin_volume_keeps_two_samples_across():
    data = _field((400, 400, 3))
    level = strided_level(Level(da.from_array(data, chunks=100), (1.0,) * 3, (0.0,) * 3),
                          50**2)
    # stride 12 across, 2 along the thin axis (3 samples: its ends are kept apart)
    assert level.shape == (34, 34, 2) and np.prod(level.shape) <= 50**2
    np.testing.assert_array_equal(level.read_all(), data[::12, ::12, ::2])


def test_the_value_range_comes_from_the_preview_samples():
    data = _field((300, 100, 100))
    data[7, 5, 5] = -1e6  # between the strided samples: not seen
    data[0, 0, 0] = np.nan
    vol = ChunkedVolume(da.from_array(data, chunks=50))
    lo, hi = vol.finite_range
    prev = vol.preview_volume().data
    assert (lo, hi) == (float(np.nanmin(prev)), float(np.nanmax(prev))) and lo > -1e6


@pytest.mark.parametrize("shape", [(129, 128, 128), (512, 512, 512)])
def test_the_budget_holds(shape):
    vol = ChunkedVolume(da.zeros(shape, chunks=128, dtype=np.uint8))
    level = vol.preview_level()
    assert np.prod(level.shape) <= PREVIEW_SAMPLES
    assert min(level.shape) >= 2
