"""The "tricubic-bspline" spline-model plugin (see :mod:`splineviz_bspline.model`), with its
OpenCL kernel family (:mod:`splineviz_bspline.kernel`)."""

from __future__ import annotations


def register(api) -> None:
    """Entry point: add the model to :data:`splineviz.core.splines.MODELS` with its kernel
    family, so :class:`splineviz.RayCaster` renders it on the OpenCL device."""
    from splineviz_bspline.kernel import TricubicBSplineFamily

    api.add_model("tricubic-bspline", "splineviz_bspline.model:TricubicBSpline",
                  label="Tricubic B-spline (C2, plugin)", degree=3, smoothness="C2",
                  kernel_family=TricubicBSplineFamily)
