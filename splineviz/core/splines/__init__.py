"""Spline models over volumes; :func:`build_spline` picks one by name from the registry
(:mod:`splineviz.core.splines.registry`)."""

from __future__ import annotations

import inspect
from importlib import import_module

from splineviz.core.splines.registry import (
    MODELS,
    ModelSpec,
    SplineOptionError,
    UnknownModelError,
    model_spec,
)
from splineviz.core.volume import Volume, VolumeError

__all__ = ["MODELS", "ModelSpec", "SplineOptionError", "UnknownModelError", "build_spline",
           "model_spec"]


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
    SplineOptionError
        An option the model does not take, or a value it cannot use.
    VolumeError
        The volume has NaN or infinite samples: a spline over them is NaN wherever they
        reach, so they are refused here rather than drawn as holes (read files with
        ``read_volume(..., nonfinite="fill")`` to replace them, with a warning).
    """
    spec = model_spec(model)
    if not isinstance(volume, Volume):
        volume = Volume(volume)
    if volume.nonfinite_count:
        raise VolumeError(f"the volume has {volume.nonfinite_count} NaN or infinite samples, "
                          f"which would make the {spec.name} spline NaN around them; replace "
                          "them first (read_volume(..., nonfinite='fill'))")
    module_name, _, cls_name = spec.target.partition(":")
    cls = getattr(import_module(module_name), cls_name)
    try:
        inspect.signature(cls).bind(volume, **kwargs)
    except TypeError:
        raise SplineOptionError(f"the {spec.name} model does not take the option(s) "
                                f"{', '.join(sorted(kwargs))}") from None
    return cls(volume, **kwargs)
