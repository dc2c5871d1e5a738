"""Spline models over volumes; :func:`build_spline` picks one by name from the registry
(:mod:`splineviz.core.splines.registry`)."""

from __future__ import annotations

from importlib import import_module

from splineviz.core.splines.registry import MODELS, ModelSpec, UnknownModelError, model_spec
from splineviz.core.volume import Volume

__all__ = ["MODELS", "ModelSpec", "UnknownModelError", "build_spline", "model_spec"]


def build_spline(volume, model: str = "to-quadratic", **kwargs):
    """Build the spline ``model`` over ``volume``.

    Parameters
    ----------
    volume : Volume or (nx, ny, nz) array
    model : str
        A key of :data:`MODELS` (``"trilinear"``, ``"super-quadratic"``, ``"cubic-c1"``,
        ``"to-quadratic"`` and plugin models).
    **kwargs
        Model options, e.g. ``k`` for ``"to-quadratic"`` (thesis Q_k, default 2).

    Returns
    -------
    Spline

    Raises
    ------
    UnknownModelError
        ``model`` is not registered.
    """
    spec = model_spec(model)
    if not isinstance(volume, Volume):
        volume = Volume(volume)
    module_name, _, cls = spec.target.partition(":")
    return getattr(import_module(module_name), cls)(volume, **kwargs)
