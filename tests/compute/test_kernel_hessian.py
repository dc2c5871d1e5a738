"""The ray caster's Hessian and gradient norm at the hits (colour by curvature in the kernel)
against the NumPy derivatives of the same spline at the same points."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.colour_by import derivative_scalars, hit_scalars

from .helpers import HAVE_CL

pytestmark = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device at all")

VOL = sv.Volume.from_function(lambda x, y, z: np.sin(2 * x) + np.cos(3 * y) * z + 0.5 * x * y * z,
                              (20, 22, 24), ((-1, 1), (-1.1, 1), (-1, 1.2)))
CAM = sv.Camera((2.2, -3.1, 1.7), (0, 0, 0), view_up=(0, 0, 1))


@pytest.mark.parametrize("model", ["trilinear", "super-quadratic", "cubic-c1", "to-quadratic"])
def test_kernel_derivatives_equal_numpy(model):
    rc = sv.RayCaster(VOL, model=model)
    rc.set_isovalue(0.3)
    frame = rc.render(CAM, size=(48, 36), hessian=True)
    hit = frame.hit
    assert hit.sum() > 300
    spline = sv.build_spline(VOL, model)
    pts = frame.position[hit]
    h, g = spline.hessian(pts), spline.gradient(pts)
    scale = np.abs(h).max()
    assert np.abs(frame.hessian[hit] - h).max() < 1e-4 * scale  # float32 in the kernel
    np.testing.assert_allclose(frame.gradient_norm[hit], np.linalg.norm(g, axis=1), rtol=1e-4)
    assert np.isnan(frame.hessian[~hit]).all()
    # the curvature from the kernel's derivatives is the NumPy one at the hits
    grad = frame.normal[hit] * frame.gradient_norm[hit][:, None]
    mean_k = derivative_scalars("mean", grad, frame.hessian[hit])
    mean_np = hit_scalars(spline, pts, "mean")
    ok = np.abs(mean_np) < 1e3  # away from near-critical points
    assert np.median(np.abs(mean_k - mean_np)[ok]) < 1e-4 * np.median(np.abs(mean_np[ok]))
    # without asking, nothing extra
    assert rc.render(CAM, size=(16, 12)).hessian is None
