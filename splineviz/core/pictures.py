"""The hook through which a scene model shows itself as a picture (notebooks, ``scene.show()``).

The scene model (:mod:`splineviz.model`) must not import the renderer (import-linter
contracts: ``model`` has no VTK), yet ``Scene._repr_png_`` and ``Scene.show()`` need a picture.
As with the registries' loader hook (:mod:`splineviz.core.registry`), one function is
installed here by the package ``splineviz`` on import: it imports
:mod:`splineviz.notebook` (model + renderer) on first use.

The objects the API returns show themselves through the same hook: a
:class:`~splineviz.core.volume.Volume` or :class:`~splineviz.core.points.PointCloud`
(``_repr_png_``: the picture of a new scene holding just that object), and meshes, which are
``pyvista.PolyData`` (docs/api.md), through IPython formatters registered by
:func:`register_formatters` (a type of another library gets its picture there, not by a
method).
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
    """Draw ``scene`` (a scene, or a volume, point cloud or mesh: see
    :func:`splineviz.notebook.as_scene`) with the installed function (see
    :func:`splineviz.notebook.show`)."""
    if _SHOW is None:
        raise PictureError("no renderer is installed to draw the scene; import splineviz first")
    return _SHOW(scene, **options)


def png(obj) -> bytes:
    """PNG bytes of the default picture of ``obj`` (what a notebook shows)."""
    return show(obj).png()


#: (module, class name) of the mesh type of the API, registered by name so that registering
#: imports no VTK; pyvista's own HTML table of the mesh is replaced by the picture (a
#: notebook shows the richest output: HTML before PNG), its text ``repr`` is kept
MESH_TYPES = (("pyvista.core.pointset", "PolyData"),)


def register_formatters(display_formatter) -> None:
    """Let IPython show meshes (``pyvista.PolyData``) as their pictures.

    Parameters
    ----------
    display_formatter : IPython.core.formatters.DisplayFormatter
        ``get_ipython().display_formatter``; ``import splineviz`` in a kernel registers there.
    """
    formatters = display_formatter.formatters
    for module, name in MESH_TYPES:
        formatters["image/png"].for_type_by_name(module, name, png)
        formatters["text/html"].for_type_by_name(module, name, _no_html)


def _no_html(_obj) -> None:
    return None
