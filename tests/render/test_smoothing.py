"""OpenCL Gaussian smoothing against scipy.ndimage.gaussian_filter."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

import splineviz as sv
from splineviz.compute.device import try_get_device
from splineviz.compute.smoothing import SmoothingError, gaussian_smooth, gaussian_weights


def test_weights_are_scipys():
    from scipy.ndimage import _filters

    w = gaussian_weights(1.7)
    ref = _filters._gaussian_kernel1d(1.7, 0, int(4.0 * 1.7 + 0.5))[::-1]
    assert np.allclose(w, ref) and abs(w.sum() - 1) < 1e-12


@pytest.mark.parametrize("sigma", [0.8, (1.5, 0.0, 2.5), 6.0])
def test_opencl_matches_scipy(sigma):
    if try_get_device("cpu") is None and try_get_device(None) is None:
        pytest.skip("no OpenCL device")
    rng = np.random.default_rng(3)
    # anisotropic shape, smaller than the kernel along one axis (reflection wraps)
    data = rng.normal(size=(23, 9, 17)).astype(np.float32) + np.linspace(0, 5, 17)
    vol = sv.Volume(data, spacing=(1, 2, 0.5), origin=(1, 2, 3))
    out = gaussian_smooth(vol, sigma)
    ref = gaussian_filter(data.astype(np.float64), sigma, mode="reflect", truncate=4.0)
    assert np.abs(out.data - ref).max() < 2e-5
    assert out.spacing == vol.spacing and out.origin == vol.origin


def test_numpy_fallback_and_errors():
    vol = sv.Volume(np.arange(27.0).reshape(3, 3, 3))
    assert np.allclose(gaussian_smooth(vol, 0, device="numpy").data, vol.data)
    for bad in (-1, float("nan"), 1000):
        with pytest.raises(SmoothingError):
            gaussian_smooth(vol, bad)
