"""Volumes, point clouds and meshes the API returns show themselves in a notebook: the exact
picture of a new scene holding just that object, framed isometric."""

import io

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.pictures import PictureError, register_formatters
from splineviz.model import Scene
from splineviz.notebook import DEFAULT_SIZE, as_scene
from splineviz.render.scene_view import render_scene


def _decode(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)))


def _framed(scene: Scene, size=DEFAULT_SIZE) -> np.ndarray:
    scene.aspect = size[0] / size[1]
    scene.frame(view="isometric")
    return render_scene(scene, size)


def _sphere_points(n=400):
    rng = np.random.default_rng(3)
    p = rng.normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


def _not_blank(image: np.ndarray) -> bool:
    return (np.abs(image.astype(int) - image[0, 0]).max(axis=2) > 30).mean() > 0.02


def test_volume_png_is_its_default_isosurface():
    # a ball: the default isovalue (Otsu's threshold) separates it from the corners
    vol = sv.Volume.from_function(lambda x, y, z: x * x + y * y + z * z, (24, 24, 24),
                                  ((-1, 1), (-1, 1), (-1, 1)))
    png = vol._repr_png_()
    expected = Scene()
    expected.add_volume(vol, "volume")
    image = _framed(expected)
    assert np.array_equal(_decode(png), image)
    assert _not_blank(image)
    assert "Volume" in repr(vol)  # the text form is untouched


def test_point_cloud_png_is_the_scene_of_its_points():
    cloud = sv.PointCloud(_sphere_points())
    pic = cloud.show(size=(160, 120))
    expected = Scene()
    expected.add_points(cloud, "points")
    image = _framed(expected, (160, 120))
    assert np.array_equal(pic.image, image) and _not_blank(image)
    assert np.array_equal(_decode(cloud._repr_png_()), _framed(expected))
    assert "PointCloud" in repr(cloud)


def test_mesh_shows_as_its_picture_in_ipython():
    pv = pytest.importorskip("pyvista")
    from IPython.core.formatters import DisplayFormatter

    mesh = pv.Sphere(theta_resolution=24, phi_resolution=12)
    formatter = DisplayFormatter()
    before, _ = formatter.format(mesh)
    assert "text/html" in before and "image/png" not in before  # pyvista's table
    register_formatters(formatter)
    data, _ = formatter.format(mesh)
    assert "text/html" not in data and data["text/plain"] == before["text/plain"]
    expected = Scene()
    faces = mesh.faces.reshape(-1, 4)[:, 1:]
    expected.add_mesh(mesh.points, faces, "mesh",
                      normals=np.asarray(mesh.point_data["Normals"], dtype=np.float64))
    image = _framed(expected)
    assert np.array_equal(_decode(data["image/png"]), image) and _not_blank(image)
    # other objects keep their formatting
    assert "image/png" not in formatter.format(np.zeros(3))[0]


def test_as_scene_takes_vertex_face_pairs_and_refuses_other_things():
    from splineviz.model import MeshNode

    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    (mesh,) = as_scene((v, np.array([[0, 1, 2]]))).of_kind(MeshNode)
    assert np.array_equal(mesh.vertices, v) and mesh.faces.tolist() == [[0, 1, 2]]
    with pytest.raises(PictureError, match="cannot show a str"):
        as_scene("bunny.ply")
