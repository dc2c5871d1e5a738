"""The "tricubic-bspline" spline-model plugin (see :mod:`splineviz_bspline.model`)."""

from __future__ import annotations


def register(api) -> None:
    """Entry point: add the model to :data:`splineviz.core.splines.MODELS`."""
    api.add_model("tricubic-bspline", "splineviz_bspline.model:TricubicBSpline",
                  label="Tricubic B-spline (C2, plugin)", degree=3, smoothness="C2")
