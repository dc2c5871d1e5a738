"""Volume rendering in render_scene and sessions (issue 30): a mesh hides what is behind it,
the isosurface is embedded, clip planes cut, a session keeps the settings."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.testfunctions import ml
from splineviz.model import Scene
from splineviz.model.session import load_scene, save_scene
from splineviz.render.scene_view import render_scene

SIZE = (120, 96)


def _scene(data=None):
    scene = Scene()
    vol = sv.Volume.from_function(ml, (21, 21, 21), ml.domain) if data is None else data
    node = scene.add_volume(vol, name="ML")
    node.show_outline = False
    scene.isosurfaces[0].visible = False
    scene.aspect = SIZE[0] / SIZE[1]
    scene.frame(view="isometric")
    return scene, node


def _sphere():
    import pyvista as pv

    s = pv.Sphere(radius=0.45, center=(0, 0, 0), theta_resolution=48, phi_resolution=48)
    return s.points, s.faces.reshape(-1, 4)[:, 1:]


def test_volume_rendering_draws_and_a_mesh_hides_what_is_behind():
    scene, node = _scene()
    plain = render_scene(scene, SIZE, device="cpu")
    node.update(volume_rendering=True, transfer_function="mri")
    shown = render_scene(scene, SIZE, device="cpu")
    assert np.abs(shown.astype(int) - plain).max(axis=2).mean() > 5
    # an opaque sphere in the volume: inside its silhouette the picture does not depend on
    # the data behind the sphere
    verts, faces = _sphere()
    scene.add_mesh(verts, faces, name="ball", opacity=1.0)
    scene.frame(view="isometric")
    with_ball = render_scene(scene, SIZE, device="cpu")
    node.update(volume_rendering=False)
    ball_only = render_scene(scene, SIZE, device="cpu")
    node.update(volume_rendering=True)
    cam = scene.camera
    data = ml(*np.meshgrid(*[np.linspace(-1, 1, 21)] * 3, indexing="ij"))
    pts = np.stack(np.meshgrid(*[np.linspace(-1, 1, 21)] * 3, indexing="ij"), -1)
    dop = np.subtract(cam.focal_point, cam.position)
    dop /= np.linalg.norm(dop)
    behind = (pts - np.asarray(cam.position)) @ dop > np.linalg.norm(cam.position) + 0.6
    data[behind] = 0.95
    other, onode = _scene(sv.Volume(data, spacing=node.data.spacing, origin=node.data.origin))
    onode.update(volume_rendering=True, transfer_function="mri")
    other.add_mesh(verts, faces, name="ball", opacity=1.0)
    other.camera.update(**scene.camera.pose())
    changed = render_scene(other, SIZE, device="cpu")
    ball = np.abs(ball_only.astype(int) - plain).max(axis=2) > 30
    assert ball.sum() > 200
    np.testing.assert_array_equal(with_ball[ball], changed[ball])
    assert not np.array_equal(with_ball[~ball], changed[~ball])


def test_clip_planes_cut_the_volume_rendering():
    scene, node = _scene()
    node.update(volume_rendering=True, transfer_function="mri")
    full = render_scene(scene, SIZE, device="cpu")
    scene.add_clip_plane((0, 0, 0), (0, 0, -1), volume=node)
    cut = render_scene(scene, SIZE, device="cpu")
    assert np.abs(full.astype(int) - cut).max(axis=2).mean() > 2


def test_session_keeps_volume_rendering(tmp_path):
    scene, node = _scene()
    # unused, the settings are not written (sessions saved before stay byte-identical)
    assert not {"volume_rendering", "transfer_function", "rendering_model",
                "rendering_shade"} & set(node.state())
    node.update(volume_rendering=True, transfer_function="ct-lungs", rendering_shade=False,
                rendering_model="trilinear")
    back = load_scene(save_scene(scene, tmp_path / "vr"))
    bnode = back.volumes[0]
    assert (bnode.volume_rendering, bnode.transfer_function, bnode.rendering_shade,
            bnode.rendering_model) == (True, "ct-lungs", False, "trilinear")


def test_bad_transfer_function_is_refused():
    _, node = _scene()
    with pytest.raises(sv.SplinevizError, match="neither a transfer function preset"):
        node.transfer_function = "bone"


def test_cli_volume_rendering(tmp_path, capsys):
    from splineviz.cli import main
    from splineviz.core.transfer_function import preset, write_paraview_json

    np.save(tmp_path / "ml.npy", sv.Volume.from_function(ml, (17, 17, 17), ml.domain).data)
    write_paraview_json(preset("cryo-em", (0, 1)), tmp_path / "tf.json")
    pictures = []
    for spec in ("mri", str(tmp_path / "tf.json")):
        out = tmp_path / "vr.png"
        rc = main(["render", str(tmp_path / "ml.npy"), "--volume-rendering", spec,
                   "--size", "48x36", "--device", "cpu", "-o", str(out)])
        assert rc == 0
        from PIL import Image

        pictures.append(np.asarray(Image.open(out)))
    assert not np.array_equal(*pictures)
    capsys.readouterr()
    for spec, msg in (("bone", "bad --volume-rendering"), (str(tmp_path / "no.json"),
                                                           "cannot read the transfer")):
        rc = main(["render", str(tmp_path / "ml.npy"), "--volume-rendering", spec, "-o",
                   str(tmp_path / "x.png")])
        err = capsys.readouterr().err
        assert rc == 2 and msg in err and len(err.strip().splitlines()) == 1


def test_edited_transfer_function_points_render_and_round_trip(tmp_path):
    """transfer_function_points replace the preset: the preset's own points give its
    picture, other points another one; a session keeps them; bad points are one sentence."""
    from splineviz.core.transfer_function import preset
    from splineviz.io.errors import SessionError
    from splineviz.model import ModelError, TransferFunctionPoints

    scene, node = _scene()
    node.update(volume_rendering=True, transfer_function="mri")
    with_preset = render_scene(scene, SIZE, device="cpu")
    tf = preset("mri", node.data.finite_range)
    node.transfer_function_points = TransferFunctionPoints.of(tf)
    assert np.array_equal(render_scene(scene, SIZE, device="cpu"), with_preset)
    op = tf.opacity_points.copy()
    op[1, 1] = 1.0  # the noise floor made opaque
    edited = TransferFunctionPoints.of(type(tf)(tf.rgb_points, op))
    node.transfer_function_points = edited
    picture = render_scene(scene, SIZE, device="cpu")
    assert np.abs(picture.astype(int) - with_preset).max(axis=2).mean() > 2

    path = save_scene(scene, tmp_path / "edited.svs")
    loaded = load_scene(path)
    assert loaded.volumes[0].transfer_function_points == edited
    assert np.array_equal(render_scene(loaded, SIZE, device="cpu"), picture)

    with pytest.raises(ModelError):
        node.transfer_function_points = {"rgb_points": [[0, 0, 0, 0]],
                                         "opacity_points": [[1, 0], [0, 1]]}
    text = path.read_text().replace('"opacity_points": [\n', '"opacity_points": [\n[2, 0.5],\n',
                                    1)
    bad = tmp_path / "bad.svs"
    bad.write_text(text)
    with pytest.raises(SessionError, match="non-decreasing") as err:
        load_scene(bad)
    assert "\n" not in str(err.value)
