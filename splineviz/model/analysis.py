"""Surface analysis of a scene's isosurfaces from their splines (no Qt, no VTK): the exact
cross-section curves of :class:`~splineviz.model.nodes.SectionNode` objects."""

from __future__ import annotations

from splineviz.core import sections
from splineviz.model.nodes import SectionNode


def isosurface_spline(scene, iso):
    """The spline of an isosurface node over its volume's active samples."""
    from splineviz.core.splines import build_spline

    return build_spline(scene.volume_of(iso).active, iso.model, **iso.model_options())


def section_curves(scene, node: SectionNode) -> list:
    """Compute (and keep on the node) the curves of a section.

    Returns
    -------
    list of :class:`~splineviz.core.sections.SectionCurve`
    """
    iso = scene.get(node.isosurface_id)
    spline = isosurface_spline(scene, iso)
    if node.plane_id is not None:
        plane = scene.get(node.plane_id)
        curves = sections.plane_section(spline, iso.isovalue, plane.origin, plane.normal)
    else:
        other = scene.get(node.other_id)
        curves = sections.surface_intersection(spline, iso.isovalue,
                                               isosurface_spline(scene, other), other.isovalue)
    node.curves = curves
    return curves
