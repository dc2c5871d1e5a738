"""Volume-rendering benchmark (issue 30): its analytic reference is Marschner-Lobb's, and
``pytest tests/bench/test_bench_dvr.py -m bench -s`` runs it small (``splineviz bench dvr``
runs it at 512^2 with bonsai)."""

import numpy as np
import pytest

from splineviz.bench.dvr import ml_value_gradient, octagon_planes
from splineviz.core.testfunctions import ml


def test_closed_form_is_marschner_lobb():
    p = np.random.default_rng(0).uniform(-1, 1, (200, 3))
    p[0] = 0.0  # the axis, where the radial derivative is 0/0
    v, g = ml_value_gradient(p)
    jet = ml.derivatives(*p.T)
    np.testing.assert_allclose(v, jet.v, atol=1e-12)
    np.testing.assert_allclose(g, jet.g, atol=1e-9)


def test_octagon_keeps_its_inner_disc():
    planes = octagon_planes(0.5)
    inside = np.array([0.45, 0.1, 0.3])
    outside = np.array([0.6, 0.0, 0.0])
    assert all(np.dot(inside - o, n) >= 0 for o, n in planes)
    assert not all(np.dot(outside - o, n) >= 0 for o, n in planes)


@pytest.mark.bench
def test_bench_dvr_quality_small(monkeypatch):
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    from splineviz.bench.dvr import quality

    rows = quality(size=(96, 96), device="cpu")
    print("\n".join(str(r) for r in rows))
    ours = [r for r in rows if not r["renderer"].startswith("vtk")]
    assert len(ours) == 24 and all(0 < r["rmse"] < 0.2 for r in ours)


def test_field_errors_show_what_reconstructions_reach():
    """The quasi-interpolants' gradients converge faster than trilinear's (order two against
    one, thesis §4.3); their values do not beat trilinear interpolation at these sample counts,
    and B-spline interpolation bounds what any reconstruction of 41^3 samples reaches."""
    from splineviz.bench.dvr import field_errors

    rows = {(r["n"], r["model"]): r for r in field_errors(
        ns=(41, 81), models=("trilinear", "cubic-c1"), points=20_000)}
    grad = {k: r["gradient_rmse"] for k, r in rows.items() if r["gradient_rmse"] is not None}
    assert grad[81, "cubic-c1"] < 0.7 * grad[81, "trilinear"]
    assert grad[41, "trilinear"] / grad[81, "trilinear"] < grad[41, "cubic-c1"] / grad[
        81, "cubic-c1"]
    value = {k: r["value_rmse"] for k, r in rows.items()}
    assert value[41, "bspline-5"] < value[41, "bspline-3"] < value[41, "trilinear"]
    assert 0.02 < value[41, "trilinear"] < 0.04
