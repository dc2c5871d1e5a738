"""The renderers of a spline isosurface: the one table of their names, labels and reach.

A spline isosurface is drawn either by the image-based ray caster in OpenCL (thesis §6.2,
:mod:`splineviz.compute.raycast`) or by hybrid cell projection in VTK's OpenGL pipeline
(thesis §6.1, :mod:`splineviz.render.cell_projection`). An isosurface node names one of the
:data:`RENDERERS` keys (``"auto"`` by default); the node's validation, sessions, the GUI's
renderer box and ``splineviz render --renderer`` all read this table, and
:func:`choose_renderer` is the one rule that turns a node's choice into the renderer that
draws it.

Cell projection draws the type-6 models (``super-quadratic``, ``cubic-c1``: the kernel
family ``"type6"``) and the quadratic C1 spline on truncated octahedra (``to-quadratic``,
family ``"to"``) in one flat colour; any other model, and colour by, is ray cast (on the
NumPy reference path where no OpenCL device exists: slow, but correct).
"""

from __future__ import annotations

from dataclasses import dataclass

from splineviz.core.errors import SplinevizError
from splineviz.core.splines.registry import model_spec


class RendererError(SplinevizError, ValueError):
    """A renderer name that is not in :data:`RENDERERS`."""


@dataclass(frozen=True)
class Renderer:
    """One entry of :data:`RENDERERS`.

    Attributes
    ----------
    name : str
        The key in code, sessions and on the command line.
    label : str
        What users see (the GUI's renderer box).
    families : tuple of str or None
        The spline kernel families it draws (:attr:`splineviz.core.splines.registry.
        ModelSpec.family`); None: every model.
    """

    name: str
    label: str
    families: tuple[str, ...] | None = None


#: the choice that picks a renderer by the machine (:func:`choose_renderer`)
AUTO = "auto"
RAY_CASTING = "ray-casting"
CELL_PROJECTION = "cell-projection"

#: renderer name -> :class:`Renderer`, in the order menus list them
RENDERERS: dict[str, Renderer] = {r.name: r for r in (
    Renderer(AUTO, "automatic (ray casting with OpenCL, else cell projection)"),
    Renderer(RAY_CASTING, "ray casting (OpenCL)"),
    Renderer(CELL_PROJECTION, "cell projection (OpenGL)", ("type6", "to")),
)}

#: other spellings accepted where a name is typed (the command line, Python)
ALIASES = {"raycast": RAY_CASTING, "ray-cast": RAY_CASTING, "raycasting": RAY_CASTING}


def renderer_name(name: str) -> str:
    """The :data:`RENDERERS` key ``name`` stands for (an :data:`ALIASES` spelling gives
    its key).

    Raises
    ------
    RendererError
        "unknown renderer 'x'; choose one of auto, ray-casting, cell-projection".
    """
    key = ALIASES.get(name, name) if isinstance(name, str) else None
    if key not in RENDERERS:
        raise RendererError(f"unknown renderer {name!r}; choose one of "
                            f"{', '.join(RENDERERS)}")
    return key


@dataclass(frozen=True)
class RendererChoice:
    """What :func:`choose_renderer` decided.

    Attributes
    ----------
    renderer : str
        ``"ray-casting"`` or ``"cell-projection"``.
    note : str
        One sentence saying why the renderer differs from the one asked for, or why the
        ray caster runs without OpenCL; ``""`` when there is nothing to say.
    """

    renderer: str
    note: str = ""


def draws(renderer: str, family: str | None) -> bool:
    """Whether ``renderer`` draws models of the kernel ``family``."""
    families = RENDERERS[renderer].families
    return families is None or family in families


def choose_renderer(choice: str, model: str, color_by: str = "none",
                    opencl: bool = True, data: str = "") -> RendererChoice:
    """The renderer that draws an isosurface of ``model`` for the node's ``choice``.

    ``"auto"`` is the OpenCL ray caster where an OpenCL device exists (``opencl``), else
    cell projection where it draws the surface. Cell projection draws the type-6 models
    without colour by (``color_by == "none"``); otherwise the surface is ray cast, and
    :attr:`RendererChoice.note` says so.

    Parameters
    ----------
    choice : str
        A :data:`RENDERERS` key or alias.
    model : str
        A key of the spline model registry.
    color_by : str
        The node's colour-by field (:data:`splineviz.core.colour_by.FIELDS`).
    opencl : bool
        Whether an OpenCL device works here.
    data : str
        What of the data cell projection cannot draw (``"a chunked volume"``, ``"an
        oblique scan"``: its tets are placed on an axis-aligned grid in memory), ``""``
        when it can.
    """
    choice = renderer_name(choice)
    spec = model_spec(model)
    projectable = draws(CELL_PROJECTION, spec.family) and color_by == "none" and not data
    numpy_path = "" if opencl or spec.family is None else (
        "no OpenCL device: ray casting on the slow NumPy reference path")
    if choice == RAY_CASTING:
        return RendererChoice(RAY_CASTING, numpy_path)
    if projectable and (choice == CELL_PROJECTION or not opencl):
        return RendererChoice(CELL_PROJECTION)
    if choice == AUTO and opencl:
        return RendererChoice(RAY_CASTING)
    if not draws(CELL_PROJECTION, spec.family):
        why = f"the model {model!r}"
    else:
        why = data or f"colour by {color_by!r}"
    reach = ("cell projection draws the type-6 models (super-quadratic, cubic-c1) of "
             f"axis-aligned in-memory volumes in one colour; {why} is ray cast")
    return RendererChoice(RAY_CASTING, "; ".join(filter(None, (reach, numpy_path))))
