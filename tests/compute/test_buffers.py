"""Filling device arrays (:func:`splineviz.compute.buffers.fill`)."""

import numpy as np
import pytest

from .helpers import HAVE_CL


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")
@pytest.mark.parametrize("dtype, value", [(np.uint16, 0xFF00), (np.uint32, 0),
                                          (np.float32, -2.5), (np.int8, -3)])
def test_fill_sets_every_element_of_the_array_alone(dtype, value):
    import pyopencl.array as cla

    from splineviz.compute.buffers import fill
    from splineviz.compute.device import get_device

    q = get_device().queue
    whole = cla.to_device(q, np.arange(40).astype(dtype))
    fill(whole[8:30], value, q)
    got = whole.get(queue=q)
    want = np.arange(40).astype(dtype)
    want[8:30] = value
    np.testing.assert_array_equal(got, want)
    fill(whole[5:5], value, q)  # an empty array is nothing to fill
