"""Spline models over volumes; :func:`build_spline` picks one by name."""

from __future__ import annotations

from importlib import import_module

from splineviz.core.volume import Volume

# model name -> "module:class"; modules import lazily
MODELS = {
    "trilinear": "splineviz.core.splines.trilinear:TrilinearSpline",
    "to-quadratic": "splineviz.core.splines.to_quadratic:TOQuadraticSpline",
    "cubic-c1": "splineviz.core.splines.cubic_c1:CubicC1Spline",
    "super-quadratic": "splineviz.core.splines.super_quadratic:SuperQuadraticSpline",
}


def build_spline(volume, model: str = "to-quadratic", **kwargs):
    """Build the spline ``model`` over ``volume``.

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array
    model : str
        One of :data:`MODELS` (``"trilinear"``, ``"super-quadratic"``, ``"cubic-c1"``,
        ``"to-quadratic"``).
    **kwargs
        Model options, e.g. ``k`` for ``"to-quadratic"`` (thesis Q_k, default 2).

    Returns
    -------
    Spline
    """
    if model not in MODELS:
        raise ValueError(f"unknown spline model {model!r}; choose one of {sorted(MODELS)}")
    if not isinstance(volume, Volume):
        volume = Volume(volume)
    module_name, _, cls = MODELS[model].partition(":")
    return getattr(import_module(module_name), cls)(volume, **kwargs)
