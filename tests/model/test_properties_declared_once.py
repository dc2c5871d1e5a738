"""Issue 24: a node's fields are the one declaration of its properties; sessions, the render
layer and the materials are derived from it, and entries nothing read are dropped on load."""

from __future__ import annotations

import ast
import json
import logging
import pickle
from pathlib import Path
from typing import Annotated

import numpy as np
import pytest
from pydantic import Field

import splineviz as sv
from splineviz.core import material as core_material
from splineviz.core import raycast_reference as ref
from splineviz.core.testfunctions import ml
from splineviz.io.errors import SessionError
from splineviz.io.session import Session, load_session, migrate, object_types
from splineviz.model import IsosurfaceNode, MeshNode, ModelError, Scene, ViewNode, schema
from splineviz.model.session import load_scene, save_scene

SRC = Path(sv.__file__).resolve().parent


def ml_volume(n=9):
    return sv.Volume.from_function(ml, (n,) * 3, ml.domain)


class GlowingNode(IsosurfaceNode):
    """An isosurface with one more property, as a new feature would add it."""

    glow: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0


@pytest.fixture
def glowing():
    """``GlowingNode`` as the node of session Isosurfaces (restored afterwards)."""
    before = schema.OBJECT_NODES["Isosurface"]
    schema.register("Isosurface", GlowingNode)
    try:
        yield GlowingNode
    finally:
        schema.register("Isosurface", *before)


def _scene_with(node_cls, tmp_path, **props):
    scene = Scene()
    np.save(tmp_path / "v.npy", ml_volume().data)
    vol = scene.add_volume(ml_volume(), "ml", path=tmp_path / "v.npy", isosurface=False)
    iso = scene.add(node_cls(volume_id=vol.id, isovalue=0.5, model="trilinear", **props))
    return scene, iso


def test_a_new_node_property_is_in_sessions_with_no_other_edit(glowing, tmp_path):
    scene, iso = _scene_with(glowing, tmp_path, glow=0.25)
    path = save_scene(scene, tmp_path / "glow.svs")
    doc = json.loads(path.read_text())
    props = doc["objects"][1]["properties"]
    assert list(props.items()) == [("isovalue", 0.5), ("model", "trilinear"), ("glow", 0.25)]
    back = load_scene(path)
    assert isinstance(back.get(iso.id), glowing) and back.get(iso.id).glow == 0.25
    # the derived schema validates it with the node's own rule
    props["glow"] = 2.0
    path.write_text(json.dumps(doc))
    with pytest.raises(SessionError, match="glow"):
        load_session(path)
    # its default is not written
    iso.glow = 0.0
    assert "glow" not in json.loads(save_scene(scene, tmp_path / "g2.svs").read_text())[
        "objects"][1]["properties"]


def test_a_new_node_property_reaches_the_render_layer(tmp_path):
    pv = pytest.importorskip("pyvista")
    from splineviz.render.scene_view import IsosurfaceView, SceneView, view_class

    scene, iso = _scene_with(GlowingNode, tmp_path)
    assert view_class(iso) is IsosurfaceView  # found through its base
    pl = pv.Plotter(off_screen=True, window_size=(32, 24))
    view = SceneView(scene, pl)
    try:
        layer = view.layers[iso.id]
        heard = []
        layer.connect(lambda _layer, what: heard.append(what))
        iso.glow = 0.5
        assert heard == ["appearance"] and layer.node.glow == 0.5
        iso.isovalue = 0.6
        assert heard[-1] == "frame" and layer.isovalue == 0.6
        # the layer holds no copy: what it reports is the node's
        iso.update(color=(0.1, 0.2, 0.3), opacity=0.5, material="metal")
        assert (layer.color, layer.opacity, layer.material) == (
            (0.1, 0.2, 0.3), 0.5, core_material.MATERIALS["metal"])
    finally:
        view.close()
        pl.close()
    count = len(heard)
    iso.glow = 0.75  # a closed view no longer listens
    assert len(heard) == count


def test_layer_setters_write_the_node_and_report_its_validation():
    from splineviz.render.isosurface import IsosurfaceLayer, LayerError

    layer = IsosurfaceLayer(ml_volume(), model="trilinear", isovalue=0.5)
    layer.set_model("cubic-c1")
    layer.set_color_map("coolwarm", "manual", (-1.0, 2.0))
    node = layer.node
    assert (node.model, node.color_map, node.color_min, node.color_max) == (
        "cubic-c1", "coolwarm", -1.0, 2.0)
    with pytest.raises(LayerError, match="unknown spline model 'quartic'"):
        layer.set_model("quartic")
    # a panel moving one end past the other: the map keeps the last valid range
    node.color_min = 3.0
    assert layer.color_limits == (-1.0, 2.0)
    node.color_max = 4.0
    assert layer.color_limits == (3.0, 4.0)


def test_the_model_name_is_checked_by_the_registry_alone():
    from splineviz.core.splines.registry import UnknownModelError, model_spec

    with pytest.raises(UnknownModelError) as registry:
        model_spec("no-such-model")
    message = str(registry.value)
    with pytest.raises(ModelError) as node:
        IsosurfaceNode(model="no-such-model")
    assert message in str(node.value)
    s = Session()
    src = s.add("Source", {"source": "marschner-lobb"})
    with pytest.raises(SessionError) as session:
        s.add("Isosurface", {"isovalue": 1.0, "model": "no-such-model"}, inputs=[src.id])
    assert message in str(session.value)


def test_one_material_table():
    from splineviz.model import MATERIALS as model_materials
    from splineviz.render.isosurface import MATERIALS as layer_materials

    table = core_material.MATERIALS
    assert model_materials is table and layer_materials is table
    assert (ref.AMBIENT, ref.DIFFUSE, ref.SPECULAR, ref.SHININESS) == \
        table[core_material.DEFAULT_MATERIAL].astuple()
    props = object_types()["Isosurface"]
    for name in table:
        assert props(isovalue=0.0, material=name).material == name
    with pytest.raises(ValueError):
        props(isovalue=0.0, material="velvet")
    # no other module assigns a material table or the Phong constants
    names = {"MATERIALS", "AMBIENT", "DIFFUSE", "SPECULAR", "SHININESS", "FRONT_COLOR",
             "BACK_COLOR"}
    where = set()
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            targets = node.targets if isinstance(node, ast.Assign) else (
                [node.target] if isinstance(node, ast.AnnAssign) else [])
            for t in targets:
                elts = t.elts if isinstance(t, ast.Tuple) else [t]
                where |= {(path.relative_to(SRC).as_posix(), e.id) for e in elts
                          if isinstance(e, ast.Name) and e.id in names}
    assert {p for p, _ in where} <= {"core/material.py", "core/raycast_reference.py"}
    assert {n for p, n in where if p == "core/raycast_reference.py"} == {
        "AMBIENT", "DIFFUSE", "SPECULAR", "SHININESS"}  # unpacked from the table


def test_node_and_schema_defaults_are_one():
    for type_name, (node_cls, _origin) in schema.OBJECT_NODES.items():
        props = object_types()[type_name]
        for field, name in schema.session_names(node_cls).items():
            node_default = node_cls.model_fields[field].get_default(call_default_factory=True)
            info = props.model_fields[name]
            if not info.is_required():
                assert info.get_default(call_default_factory=True) == node_default, (
                    type_name, field)
    # what a document without a model, a colour or show_edges means, and the look of new
    # objects, which a session writes out
    assert IsosurfaceNode().model == "to-quadratic" and MeshNode().show_edges is False
    scene = Scene()
    mesh = scene.add_mesh(np.eye(3), [[0, 1, 2]], "m")
    assert mesh.show_edges and mesh.state()["show_edges"] is True
    assert scene.view.background == ref.BACKGROUND != ViewNode().background


def test_sessions_pickle_for_worker_processes():
    s = Session()
    src = s.add("Source", {"source": "marschner-lobb"})
    s.add("Isosurface", {"isovalue": 0.3, "color_by": "mean"}, inputs=[src.id])
    assert pickle.loads(pickle.dumps(s)) == s


def test_entries_nothing_read_are_dropped_on_load_with_a_warning(tmp_path, caplog):
    np.save(tmp_path / "v.npy", ml_volume().data)
    np.save(tmp_path / "p.npy", np.zeros(3))
    doc = {"format": "splineviz-session", "schema_version": 4, "objects": [
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
        {"id": "pts", "type": "PointsFile", "properties": {"path": "p.npy"}},
        {"id": "r", "type": "Remesh", "inputs": ["pts"], "properties": {"rho": 0.5}},
        {"id": "c", "type": "ClipPlane", "inputs": ["v", "r"], "properties": {}}],
        "views": [{"id": "view1", "size": [640, 480], "hidden": ["r"],
                   "layout": {"row": 0, "col": 0, "row_span": 2, "col_span": 1}}]}
    before = json.dumps(doc)
    with caplog.at_level(logging.WARNING, logger="splineviz.io.session"):
        lifted = migrate(doc)
    assert json.dumps(doc) == before  # the input is not edited
    assert [o["id"] for o in lifted["objects"]] == ["v", "pts", "c"]
    assert lifted["objects"][2]["inputs"] == ["v"]
    assert lifted["views"][0] == {"id": "view1", "hidden": [], "layout": {"row": 0, "col": 0}}
    messages = [r.getMessage() for r in caplog.records]
    assert len(messages) == 3  # Remesh, size, row_span (a span of 1 is no setting)
    assert "Remesh" in messages[0] and all("\n" not in m for m in messages)


def test_lights_round_trip_in_documents_and_are_reported_when_loaded(tmp_path, caplog):
    np.save(tmp_path / "v.npy", ml_volume().data)
    doc = {"format": "splineviz-session", "schema_version": 4, "objects": [
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}}],
        "views": [{"id": "view1", "lights": [{"type": "scene", "intensity": 0.5}]}]}
    (tmp_path / "l.svs").write_text(json.dumps(doc))
    with caplog.at_level(logging.WARNING, logger="splineviz.model.session"):
        load_scene(tmp_path / "l.svs")
    assert any("lights" in r.getMessage() for r in caplog.records)


def test_gradient_background_is_shown_and_saved(tmp_path):
    pytest.importorskip("pyvista")
    from splineviz.render.scene_view import render_scene

    scene = Scene()
    scene.view.update(background=(0.0, 0.0, 0.0), background2=(1.0, 1.0, 1.0),
                      show_axes=False, show_scale=False)
    img = render_scene(scene, (16, 32)).astype(int)
    assert img[-1].mean() < 40 and img[0].mean() > 215  # dark bottom, light top
    np.save(tmp_path / "v.npy", ml_volume().data)
    scene.add_volume(ml_volume(), "ml", path=tmp_path / "v.npy", isosurface=False)
    back = load_scene(save_scene(scene, tmp_path / "g.svs"))
    assert back.view.background2 == (1.0, 1.0, 1.0)


def test_view_documents_mean_what_the_view_nodes_mean():
    # the views of a document keep io's own layout (lights, cells, hidden objects); their
    # camera and display entries are the camera and view nodes' properties
    from splineviz.io.session import CameraState, View
    from splineviz.model import CameraNode

    for node_cls, doc_cls in ((CameraNode, CameraState), (ViewNode, View)):
        for name, info in node_cls.properties().items():
            assert doc_cls.model_fields[name].get_default() == info.get_default(), name
