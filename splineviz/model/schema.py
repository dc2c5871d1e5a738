"""The session schema of pipeline objects, derived from the scene nodes.

Each session object type is the node it becomes (:data:`OBJECT_NODES`) plus, for data read
from somewhere, io's declaration of where from (a file and its read options, a plugin's
source: :mod:`splineviz.io.session`'s ``*Origin`` models). The properties model of a type is
made here from the node's :meth:`~splineviz.model.nodes.Node.properties`: the same types,
defaults and validators, in the same order, under their session names (a field's alias),
with the node's ``document_rules``. Importing this module registers the models with
:func:`splineviz.io.session.register_object_type`, so a property added to a node is in the
schema with no other edit.
"""

from __future__ import annotations

import copy

from pydantic import BaseModel, ConfigDict, create_model, model_validator
from pydantic_core import PydanticUndefined

from splineviz.io.session import (
    CameraBase,
    MeshFileOrigin,
    PointsFileOrigin,
    SourceOrigin,
    VolumeFileOrigin,
    register_animation_model,
    register_camera_model,
    register_object_type,
)
from splineviz.model.animation import Animation
from splineviz.model.nodes import (
    CameraNode,
    ClipPlaneNode,
    IsosurfaceNode,
    MeshNode,
    Node,
    PointsNode,
    SectionNode,
    VolumeNode,
    is_required_in_documents,
)


class _Properties(BaseModel):
    """Base of the derived models: unknown keys refused, as everywhere in a session."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)


#: session object type -> (node class, model of where its data comes from or None)
OBJECT_NODES: dict[str, tuple[type[Node], type[BaseModel] | None]] = {
    "VolumeFile": (VolumeNode, VolumeFileOrigin),
    "Source": (VolumeNode, SourceOrigin),
    "PointsFile": (PointsNode, PointsFileOrigin),
    "MeshFile": (MeshNode, MeshFileOrigin),
    "Isosurface": (IsosurfaceNode, None),
    "ClipPlane": (ClipPlaneNode, None),
    "Section": (SectionNode, None),
}


def session_names(node_cls: type[Node]) -> dict[str, str]:
    """``{field name: session name}`` of a node class's plain properties, in field order."""
    return {k: f.alias or k for k, f in node_cls.properties().items()}


def _field(info):
    # the node's declaration under its session name: the derived model has no aliases
    f = copy.copy(info)
    f.alias = f.validation_alias = f.serialization_alias = f.alias_priority = None
    if is_required_in_documents(info):
        f.default = PydanticUndefined
    return f.annotation, f


def properties_model(type_name: str, node_cls: type[Node],
                     origin: type[BaseModel] | None = None,
                     model_name: str | None = None) -> type[BaseModel]:
    """The model (called ``model_name``, default ``<type_name>Props``) of the properties
    of session objects of ``type_name``: the fields of ``origin`` (where the data comes
    from, or another io base), then the node's properties."""
    fields = {session_names(node_cls)[k]: _field(f) for k, f in node_cls.properties().items()}
    rules = node_cls.document_rules
    validators = {}
    if rules:
        def _rules(self):
            values = self.__dict__
            for holds, message in rules:
                if not holds(values):
                    raise ValueError(message)
            return self

        validators["_document_rules"] = model_validator(mode="after")(_rules)
    return create_model(model_name or f"{type_name}Props", __base__=origin or _Properties,
                        __validators__=validators, __module__=__name__, **fields)


#: session object type -> its properties model
PROPERTIES: dict[str, type[BaseModel]] = {}


def register(type_name: str, node_cls: type[Node], origin: type[BaseModel] | None = None):
    """Make ``node_cls`` the node of session objects of ``type_name`` (an extension, or a
    subclass with more properties) and register the properties model derived from it;
    returns that model."""
    OBJECT_NODES[type_name] = (node_cls, origin)
    model = PROPERTIES[type_name] = properties_model(type_name, node_cls, origin)
    # a module attribute, so that sessions pickle (a worker process reads their data)
    globals()[model.__name__] = model
    register_object_type(type_name, PROPERTIES[type_name])
    return PROPERTIES[type_name]


for _name, (_node, _origin) in list(OBJECT_NODES.items()):
    register(_name, _node, _origin)

#: the model of a view's camera in a session: the camera node's properties
CameraState = properties_model("Camera", CameraNode, CameraBase, model_name="CameraState")
register_camera_model(CameraState)

#: the model of a session's animation: the scene model's own
register_animation_model(Animation)
