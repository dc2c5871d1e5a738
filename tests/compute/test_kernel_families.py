"""The ray caster by kernel family (issue 24): the registry of families, the facade without
family branches, a plugin's family through ``api.add_model``, the device limits and the
64-bit sample offsets."""

import inspect
import re
from types import SimpleNamespace

import numpy as np
import pytest

from splineviz.compute import raycast
from splineviz.compute.raycast import (
    KERNEL_FAMILIES,
    CustomKernelFamily,
    KernelFamily,
    RayCaster,
    RayCastError,
    family_class,
    kernel_define,
)
from splineviz.compute.raycast import caster as caster_module
from splineviz.core.splines import MODELS, ModelSpec
from splineviz.io.errors import PluginError
from splineviz.plugins import PluginAPI

from .helpers import HAVE_CL, cameras, marschner_lobb

needs_cl = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
BUILT_IN = {"trilinear": "MODEL_TRILINEAR", "super-quadratic": "MODEL_TYPE6",
            "cubic-c1": "MODEL_TYPE6", "to-quadratic": "MODEL_TO"}


@pytest.fixture(scope="module")
def ml():
    return marschner_lobb(17)


def test_every_built_in_model_has_its_family():
    for model, define in BUILT_IN.items():
        cls = family_class(model)
        assert cls is KERNEL_FAMILIES[MODELS[model].family]
        assert kernel_define(model) == define == cls.define
        assert cls.ghost_layers == MODELS[model].ghost_layers
        assert cls.centred == MODELS[model].centred_cells


def test_the_core_registry_names_no_opencl_define():
    from splineviz.core.splines import registry

    src = inspect.getsource(registry)
    assert "MODEL_" not in src and "KERNEL_FAMILIES =" not in src


def test_the_facade_has_no_family_or_model_branches():
    # the code, without the docstring examples (which name a model)
    src = "\n".join(line for line in inspect.getsource(caster_module).splitlines()
                    if not line.lstrip().startswith(">>>"))
    assert "_family ==" not in src and "MODEL_" not in src.replace("MODEL_CUSTOM", "")
    names = "|".join(re.escape(m) for m in (*BUILT_IN, "tricubic-bspline", "type6", "to"))
    assert not re.search(rf'(==|!=|\bin)\s*[(\[{{]?\s*"({names})"', src)
    assert not re.search(r"self\.model\s*(==|!=|in\b)", src)


def test_a_model_without_a_family_renders_on_numpy(monkeypatch, ml):
    vol, iso = ml
    monkeypatch.setitem(MODELS, "numpy-only", ModelSpec(
        "numpy-only", "splineviz.core.splines.trilinear:TrilinearSpline"))
    rc = RayCaster(vol, model="numpy-only")
    assert rc.family is None and rc.stats["path"] == "numpy"
    rc.set_isovalue(iso)
    assert rc.render(cameras(vol)[0], (12, 9)).hit.any()


class _Family(CustomKernelFamily):
    name = "test-family"
    source = ("splineviz_test_missing", "none.cl")
    ghost_layers = 1

    def device_samples(self, rc):
        return np.pad(rc.volume.data, 1, mode="edge")


def test_a_plugin_registers_a_kernel_family_and_a_failure_rolls_it_back():
    api = PluginAPI("test-plugin")
    api.add_model("test-model", "splineviz.core.splines.trilinear:TrilinearSpline",
                  kernel_family=_Family)
    try:
        api._commit()
        assert MODELS["test-model"].family == "test-family"
        assert KERNEL_FAMILIES["test-family"] is _Family
        assert family_class("test-model") is _Family
    finally:
        for _, _, undo in api._staged:
            undo()
    assert "test-model" not in MODELS and "test-family" not in KERNEL_FAMILIES


@pytest.mark.parametrize("bad", [KernelFamily, object, "MODEL_X"])
def test_a_kernel_family_that_is_not_a_custom_family_is_refused(bad):
    api = PluginAPI("test-plugin")
    with pytest.raises(PluginError, match="CustomKernelFamily"):
        api.add_model("test-model", "m:C", kernel_family=bad)


@needs_cl
def test_a_family_without_its_source_is_one_clear_error(monkeypatch, ml):
    vol, _ = ml
    monkeypatch.setitem(MODELS, "test-model", ModelSpec(
        "test-model", "splineviz.core.splines.trilinear:TrilinearSpline",
        family="test-family"))
    monkeypatch.setitem(KERNEL_FAMILIES, "test-family", _Family)
    with pytest.raises(raycast.KernelFamilyError, match="no OpenCL source"):
        RayCaster(vol, model="test-model", device="cpu")


@needs_cl
@pytest.mark.parametrize("model", list(BUILT_IN))
def test_64_bit_sample_offsets_give_the_same_frames(model, ml, monkeypatch):
    """``OFFSET64`` (taken past MAX_SAMPLES device samples, here lowered to force it on a
    small volume) computes the same offsets in 64 bits: the same frames, bit for bit."""
    vol, iso = ml
    cam = cameras(vol)[1]
    want = RayCaster(vol, model=model, device="cpu")
    assert not want.limits().offsets_64 and "OFFSET64" not in want._defines()
    want.set_isovalue(iso)
    monkeypatch.setattr(caster_module, "MAX_SAMPLES", 1000)
    rc = RayCaster(vol, model=model, device="cpu")
    assert rc.limits().offsets_64 and rc._defines()["OFFSET64"] == 1
    rc.set_isovalue(iso)
    hess = model != "trilinear"
    a, b = want.render(cam, (40, 30), hessian=hess), rc.render(cam, (40, 30), hessian=hess)
    assert a.hit.sum() > 100
    for name in ("hit", "color", "depth", "position", "normal", "hessian"):
        x, y = getattr(a, name), getattr(b, name)
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=name)
    assert np.array_equal(want.skip_volume(), rc.skip_volume())


def _device(global_bytes, alloc_bytes):
    return SimpleNamespace(name="a simulated device", device=SimpleNamespace(
        global_mem_size=global_bytes, max_mem_alloc_size=alloc_bytes))


@needs_cl
@pytest.mark.parametrize("model", ["trilinear", "cubic-c1"])
def test_limits_decide_refusal_and_64_bit_acceptance(model, ml, monkeypatch):
    """A volume past 2^31 device samples is accepted (64-bit offsets) by a device that holds
    it and refused by one that does not: simulated devices, whatever the real one reports."""
    vol, _ = ml
    rc = RayCaster(vol, model=model, device="cpu")
    shape = (1300, 1300, 1300)
    big = _device(141 * 2**30, 141 * 2**30)  # an H200
    monkeypatch.setattr(rc, "_device", big)
    lim = rc.limits(shape, itemsize=1)
    assert lim.samples > 2**31 - 1 and lim.offsets_64 and lim.fits
    assert lim.need == rc.device_bytes(shape, rc._grid(shape), 1)
    rc._check_device_memory(shape, rc._grid(shape), itemsize=1)  # accepted
    small = _device(2 * 2**30, 2**30)
    monkeypatch.setattr(rc, "_device", small)
    lim = rc.limits(shape, itemsize=1)
    assert lim.offsets_64 and not lim.fits
    with pytest.raises(RayCastError, match="GiB of device memory"):
        rc._check_device_memory(shape, rc._grid(shape), itemsize=1)


def test_limits_exist_on_the_opencl_path_only(ml):
    vol, _ = ml
    with pytest.raises(RayCastError, match="OpenCL path"):
        RayCaster(vol, model="cubic-c1", device="numpy").limits()


@needs_cl
def test_a_family_whose_bricks_carry_another_spline_refuses_a_placement(ml, monkeypatch):
    from splineviz.core.bricks import BrickGrid

    vol, iso = ml
    rc = RayCaster(vol, model="trilinear", device="cpu")
    rc.set_isovalue(iso)
    monkeypatch.setattr(rc.family, "bricks", False)
    grid = BrickGrid.split(vol.shape, (1, 1, 1), 0)
    placement = grid.placement(next(iter(grid)), vol.origin)
    with pytest.raises(RayCastError, match="cannot be rendered in bricks"):
        rc.render(cameras(vol)[0], (8, 6), placement=placement)



@needs_cl
def test_whole_grid_passes_past_32_bit_cell_indices_are_refused(ml, monkeypatch):
    vol, iso = ml
    rc = RayCaster(vol, model="cubic-c1", device="cpu")
    rc.set_isovalue(iso)
    monkeypatch.setattr(caster_module, "MAX_CELLS", 1000)
    for call in (rc.classify_all, rc.skip_volume):
        with pytest.raises(RayCastError, match="32-bit indices"):
            call()
    assert rc.render(cameras(vol)[0], (16, 12)).hit.any()  # frames need no such pass
