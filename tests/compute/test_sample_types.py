"""Integer data stay in a small exact type on the device (issue 12): the same frames as
float32 samples, with 4x (uint8, trilinear) or 2x (int16, padded type-6) less memory."""

import numpy as np
import pytest

from splineviz.compute import raycast
from splineviz.compute.raycast import RayCaster, sample_type_for
from splineviz.core.volume import Volume

from .helpers import HAVE_CL, cameras, load_volume


def test_sample_type_is_the_smallest_exact_one():
    u8 = np.array([[[0, 255], [3, 4]], [[7, 9], [1, 2]]], np.float32)
    assert sample_type_for(u8, 0) == (np.uint8, "uchar")
    assert sample_type_for(u8, 1) == (np.int16, "short")  # ghosts go below 0 and above 255
    assert sample_type_for(u8, 3)[1] == "float"  # 3 ghost layers may leave int16
    assert sample_type_for(u8 * 200, 0) == (np.uint16, "ushort")
    assert sample_type_for(u8 - 1000, 0) == (np.int16, "short")
    assert sample_type_for(u8 + 0.5, 0)[1] == "float"
    nan = u8.copy()
    nan[0, 0, 0] = np.nan
    assert sample_type_for(nan, 0)[1] == "float"


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
@pytest.mark.parametrize("model,kind,itemsize", [("trilinear", "uchar", 1),
                                                 ("cubic-c1", "short", 2)])
def test_small_sample_type_gives_the_float_frames(monkeypatch, model, kind, itemsize):
    vol = load_volume("tooth.nrrd")
    vol = Volume(vol.data[::2, ::2, ::2], spacing=np.asarray(vol.spacing) * 2, origin=vol.origin)
    cam = cameras(vol)[0]
    small = RayCaster(vol, model=model)
    assert small._sample_type[1] == kind and small._data.dtype.itemsize == itemsize
    small.set_isovalue(100.5)
    got = small.render(cam, (96, 72))
    monkeypatch.setattr(raycast.samples, "sample_type_for",
                        lambda data, ghost: (np.float32, "float"))
    ref = RayCaster(vol, model=model)
    assert ref._data.dtype == np.float32
    ref.set_isovalue(100.5)
    want = ref.render(cam, (96, 72))
    assert want.hit.sum() > 500
    np.testing.assert_array_equal(got.hit, want.hit)
    np.testing.assert_array_equal(got.depth, want.depth)
    np.testing.assert_array_equal(got.color, want.color)
