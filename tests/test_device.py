"""OpenCL device choice, the SPLINEVIZ_DEVICE override, the NumPy fallback and program caching."""

import numpy as np
import pytest

from splineviz.compute import device as devmod
from splineviz.compute import program as progmod


def _has_opencl():
    try:
        devmod.get_device("auto")
        return True
    except devmod.NoDeviceError:
        return False


needs_cl = pytest.mark.skipif(not _has_opencl(), reason="no OpenCL device at all")


def test_env_override_numpy_gives_fallback_without_warning(monkeypatch):
    monkeypatch.setenv(devmod.ENV_VAR, "numpy")
    assert devmod.resolve_preference(None) == "numpy"
    assert devmod.try_get_device() is None  # explicit request: no warning (warnings are errors)
    with pytest.raises(devmod.NoDeviceError):
        devmod.get_device()


def test_unknown_device_name_warns_once_and_falls_back():
    name = "no-such-device-xyz"
    with pytest.warns(devmod.DeviceFallbackWarning, match="NumPy reference path"):
        assert devmod.try_get_device(name) is None
    assert devmod.try_get_device(name) is None  # second time: silent (warnings are errors)
    with pytest.raises(devmod.NoDeviceError, match="no OpenCL device matches"):
        devmod.get_device(name)


@needs_cl
def test_auto_prefers_gpu_and_explicit_argument_beats_env(monkeypatch):
    import pyopencl as cl

    kinds = {devmod._kind(cl, d) for p in cl.get_platforms() for d in p.get_devices()}
    dev = devmod.get_device("auto")
    assert dev.kind == ("gpu" if "gpu" in kinds else dev.kind)
    monkeypatch.setenv(devmod.ENV_VAR, "numpy")
    assert devmod.get_device(dev.kind).name == dev.name
    # a name substring selects too
    sub = dev.device.name.strip().split()[0].lower()
    assert devmod.get_device(sub).name == dev.name
    assert devmod.get_device("auto") is devmod.get_device("AUTO")  # cached


@needs_cl
def test_program_defines_and_cache(tmp_path, monkeypatch):
    import pyopencl as cl

    dev = devmod.get_device()
    src = tmp_path / "splineviz_test_kernel.cl"
    src.write_text(
        "__kernel void k(__global float *x)"
        " { int i = get_global_id(0); x[i] = x[i] * SCALE + OFF; }"
    )
    monkeypatch.setattr(progmod, "kernel_source", lambda name: src.read_text())
    before = progmod.cache_size()
    p1 = progmod.get_program(dev.context, "t", {"SCALE": 2.5, "OFF": 1})
    p2 = progmod.get_program(dev.context, "t", {"OFF": 1, "SCALE": 2.5})
    assert p1 is p2 and progmod.cache_size() == before + 1
    x = np.arange(8, dtype=np.float32)
    buf = cl.Buffer(dev.context, cl.mem_flags.READ_WRITE | cl.mem_flags.COPY_HOST_PTR, hostbuf=x)
    p1.k(dev.queue, x.shape, None, buf)
    out = np.empty_like(x)
    cl.enqueue_copy(dev.queue, out, buf)
    np.testing.assert_allclose(out, x * 2.5 + 1)
    p3 = progmod.get_program(dev.context, "t", {"SCALE": 3.0, "OFF": 1})
    assert p3 is not p1


def test_build_options_are_stable_and_checked():
    assert progmod.build_options({"B": True, "A": 0.5}) == ("-DA=0.5f", "-DB=1")
    with pytest.raises(progmod.KernelBuildError):
        progmod.build_options({"bad name": 1})
    with pytest.raises(progmod.KernelBuildError, match="no OpenCL kernel file"):
        progmod.kernel_source("does_not_exist")


@needs_cl
def test_build_error_carries_log(tmp_path, monkeypatch):
    dev = devmod.get_device()
    monkeypatch.setattr(progmod, "kernel_source", lambda name: "__kernel void k( { syntax")
    with pytest.raises(progmod.KernelBuildError, match="failed to build"):
        progmod.get_program(dev.context, "broken")
