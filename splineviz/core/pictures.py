"""The hook through which a scene model shows itself as a picture (notebooks, ``scene.show()``).

The scene model (:mod:`splineviz.model`) must not import the renderer (import-linter
contracts: ``model`` has no VTK), yet ``Scene._repr_png_`` and ``Scene.show()`` need a picture.
As with the registries' loader hook (:mod:`splineviz.core.registry`), one function is
installed here by the package ``splineviz`` on import: it imports
:mod:`splineviz.notebook` (model + renderer) on first use.
"""

from __future__ import annotations

from collections.abc import Callable

from splineviz.core.errors import SplinevizError

_SHOW: Callable | None = None


class PictureError(SplinevizError, RuntimeError):
    """No renderer is installed to draw a scene."""


def set_show(show: Callable | None) -> Callable | None:
    """Install ``show(scene, **options)``, the function that draws a scene; returns the
    previous one."""
    global _SHOW
    previous, _SHOW = _SHOW, show
    return previous


def show(scene, **options):
    """Draw ``scene`` with the installed function (see :func:`splineviz.notebook.show`)."""
    if _SHOW is None:
        raise PictureError("no renderer is installed to draw the scene; import splineviz first")
    return _SHOW(scene, **options)
