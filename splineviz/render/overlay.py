"""What a view is computing, in words: :func:`describe` (shown over the view by
:class:`splineviz.gui.overlay.ViewOverlay`).

While the exact frame of a layer is being computed the view shows an older picture: a
preview from a cheaper model, a coarser image of the exact surface, or the last picture of a
state that changed since (stale). :func:`describe` says which, per layer, in two lines
(``"computing <model> (n %) - Esc cancels"``, ``"showing <what>"``).
"""

from __future__ import annotations


def model_label(name: str) -> str:
    """The label users see for the spline model ``name`` (the name itself when unknown)."""
    from splineviz.core.splines.registry import MODELS

    spec = MODELS.get(name)
    return name if spec is None else spec.label


def shown_description(layer, rf, stand_in: bool = False) -> str:
    """What the view shows of ``layer`` (a :class:`~splineviz.render.isosurface.
    IsosurfaceLayer`) while its exact frame is due: ``rf`` is the shown
    :class:`~splineviz.render.isosurface.RenderedFrame` or None; ``stand_in``: a
    cell-projected surface's trilinear stand-in shows instead."""
    if stand_in:
        return "the trilinear stand-in (flying edges of the samples)"
    if rf is None:
        return "nothing shown yet"
    if rf.state != layer.state:
        return f"stale picture of {model_label(rf.model)}" if rf.model else "stale picture"
    share = f"{rf.scale:.0%} resolution"
    if rf.path == "preview":
        on = f" on {rf.source}" if rf.source else ""
        return f"preview from {model_label(rf.model)}{on}, {share}"
    return f"coarser image, {share}" if not rf.final else "exact picture of another view"


def describe(layer, rf, fraction: float | None, cancelled: bool,
             stand_in: bool = False) -> str:
    """Two lines about ``layer``'s frame being computed (see module docstring).

    Parameters
    ----------
    layer : IsosurfaceLayer
    rf : RenderedFrame or None
        The frame shown now.
    fraction : float in [0, 1] or None
        Of the exact frame done (None: not known).
    cancelled : bool
        The user gave up the exact frame (Esc): it is not computed until the next change.
    stand_in : bool
        The view shows the surface's trilinear stand-in (cell projection, see
        :meth:`splineviz.render.scene.SplineScene.shows_stand_in`).
    """
    label = model_label(layer.model)
    shown = f"showing {shown_description(layer, rf, stand_in)}"
    if cancelled:
        return f"{label}: cancelled (any change computes it again)\n{shown}"
    percent = "" if fraction is None else f" ({100 * fraction:.0f} %)"
    return f"computing {label}{percent} - Esc cancels\n{shown}"
