"""The scene model: evented nodes for everything a scene holds (no Qt, no VTK).

* :mod:`splineviz.model.nodes` -- volumes, isosurfaces, point clouds, meshes, clip planes,
  camera and view settings as :class:`psygnal.EventedModel` nodes;
* :mod:`splineviz.model.scene` -- :class:`Scene`, the container with ids and events;
* :mod:`splineviz.model.session` -- sessions as ``to_session`` / ``apply_session`` of a scene.

The GUI's panels, the VTK scene (:mod:`splineviz.render`) and the command line are views of
one :class:`Scene`.
"""

from splineviz.model.nodes import (
    MATERIALS,
    MAX_SIGMA,
    PALETTE,
    SIDES,
    CameraNode,
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    ModelError,
    Node,
    PointsNode,
    SectionNode,
    TransferFunctionPoints,
    ViewNode,
    VolumeNode,
)
from splineviz.model.scene import STANDARD_VIEWS, Scene

__all__ = ["MATERIALS", "MAX_SIGMA", "PALETTE", "SIDES", "STANDARD_VIEWS", "CameraNode",
           "ClipPlaneNode", "IsosurfaceNode", "MeshNode", "ModelError", "Node", "PointsNode",
           "Scene",
           "SectionNode", "TransferFunctionPoints", "ViewNode", "VolumeNode"]
