"""OpenCL failures injected into pyopencl: a kernel that does not build is a clear
KernelBuildError; a buffer the device cannot allocate or a lost device makes the render
layer fall back to the NumPy reference path with a SplinevizWarning, and the picture is the
one the NumPy path gives."""

import warnings

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.core.testfunctions import ml

cl = pytest.importorskip("pyopencl")

from splineviz.compute import program  # noqa: E402
from splineviz.compute.device import try_get_device  # noqa: E402


def _device():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return try_get_device("auto")


pytestmark = pytest.mark.skipif(_device() is None, reason="no OpenCL device")

VOL = sv.Volume.from_function(ml, (13, 13, 13), ml.domain)
CAM = sv.Camera((3.0, 2.5, 2.0), (0.0, 0.0, 0.0))


@pytest.fixture(autouse=True)
def fresh_programs():
    """Programs and kernels are cached per context: a fault must meet an empty cache."""
    saved = dict(program._cache), dict(program._kernels)
    program._cache.clear()
    program._kernels.clear()
    yield
    program._cache.clear()
    program._kernels.clear()
    program._cache.update(saved[0])
    program._kernels.update(saved[1])


def _raise(exc):
    def fail(*args, **kwargs):
        raise exc

    return fail


def test_build_failure_is_a_clear_error(monkeypatch, tried):
    monkeypatch.setattr(cl.Program, "build",
                        _raise(cl.RuntimeError("clBuildProgram failed: BUILD_PROGRAM_FAILURE")))
    with pytest.raises(SplinevizError, match="failed to build") as info:
        rc = sv.RayCaster(VOL, "trilinear", device="auto")
        rc.set_isovalue(ml.isovalue)
        rc.render(CAM, (24, 18))
    assert "\n" not in str(info.value)
    tried["opencl faults"] += 1


def _layer_frame(**kw):
    from splineviz.render.isosurface import IsosurfaceLayer, ViewState

    layer = IsosurfaceLayer(VOL, "trilinear", isovalue=ml.isovalue, device="auto", **kw)
    return layer, layer.compute(ViewState(CAM, (24, 18)))


@pytest.fixture(scope="module")
def numpy_picture():
    from splineviz.render.isosurface import IsosurfaceLayer, ViewState

    layer = IsosurfaceLayer(VOL, "trilinear", isovalue=ml.isovalue, device="numpy")
    return layer.compute(ViewState(CAM, (24, 18))).frame


@pytest.mark.parametrize("fault", ["buffer", "lost"])
def test_device_failure_falls_back_to_numpy(monkeypatch, fault, numpy_picture, tried):
    if fault == "buffer":
        def refuse(*args, **kwargs):
            raise cl.MemoryError("clCreateBuffer failed: MEM_OBJECT_ALLOCATION_FAILURE")

        monkeypatch.setattr(cl, "Buffer", refuse)
    else:
        monkeypatch.setattr(cl.Kernel, "__call__",
                            _raise(cl.LogicError("clEnqueueNDRangeKernel failed: "
                                                 "DEVICE_NOT_AVAILABLE")))
    with pytest.warns(SplinevizWarning, match="OpenCL device failed"):
        layer, rendered = _layer_frame()
    assert rendered.path == "numpy"
    np.testing.assert_array_equal(rendered.frame.hit, numpy_picture.hit)
    tried["opencl faults"] += 1
