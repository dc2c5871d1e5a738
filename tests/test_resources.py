"""The shipped resources: icons that Qt draws, example sessions that load and render.

Every icon :mod:`splineviz.resources` lists is a valid, self-contained SVG that Qt renders
to a non-empty picture (and re-colours through ``currentColor``); every example session
opens synthetic data only, is exactly what the app would write for its scene, frames the
whole data box, and renders to a picture with an isosurface in it.
"""

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from splineviz import resources as res
from splineviz.core.errors import SplinevizError

SVG_NS = "{http://www.w3.org/2000/svg}"
SIZE = (160, 120)
#: examples the issue asks for (more may be shipped)
REQUIRED_SESSIONS = ("marschner-lobb", "two-surfaces-clipped", "models-compared")


# -- icons ------------------------------------------------------------------------------


def test_resources_folder_is_the_top_level_one():
    assert res.RESOURCES.is_dir() and res.RESOURCES.name == "resources"
    assert res.ICONS_DIR.is_dir() and res.SESSIONS_DIR.is_dir()


def test_every_listed_icon_is_shipped_and_nothing_else():
    assert set(res.ICONS) == set(res.icon_names())
    assert set(res.VIEW_ICONS.values()) <= set(res.TOOLBAR_ICONS)
    from splineviz.model import STANDARD_VIEWS

    assert set(res.VIEW_ICONS) == set(STANDARD_VIEWS)


@pytest.mark.parametrize("name", res.ICONS)
def test_icon_is_self_contained_svg(name):
    path = res.icon_path(name)
    assert path.suffix == ".svg" and path.parent == res.ICONS_DIR
    root = ET.parse(path).getroot()
    assert root.tag == f"{SVG_NS}svg"
    box = root.get("viewBox").split()
    assert box[:2] == ["0", "0"] and box[2] == box[3]  # square
    text = path.read_text(encoding="utf-8")
    for forbidden in ("<script", "href=", "<image", "<foreignObject", "@import"):
        assert forbidden not in text, f"{name}: {forbidden}"
    assert root.find(f"{SVG_NS}title") is not None  # named for accessibility
    if name in res.TOOLBAR_ICONS:
        assert box == ["0", "0", "24", "24"]
        assert root.get("color", "").startswith("#") and "currentColor" in text


def test_icon_path_errors_name_the_icon_and_the_choices():
    with pytest.raises(res.ResourceError, match="'no-such-icon'.*icons: .*open") as info:
        res.icon_path("no-such-icon")
    assert isinstance(info.value, SplinevizError)
    for bad in ("../sessions/marschner-lobb", "icons/open", ""):
        with pytest.raises(res.ResourceError):
            res.icon_path(bad)


def test_icon_svg_recolours_only_the_root_colour():
    grey = res.icon_svg("view-px").decode()
    white = res.icon_svg("view-px", "#fff").decode()
    assert white == grey.replace('color="#737d8c"', 'color="#fff"', 1) and white != grey
    assert "#3b8ede" in white  # the accent stays
    with pytest.raises(ValueError, match="colour"):
        res.icon_svg("open", '"/><script>')


@pytest.fixture
def qt_app(request):
    """A Qt application for drawing SVGs (pytest-qt's ``qapp``), or a skip."""
    pytest.importorskip("PySide6.QtSvg")
    pytest.importorskip("pytestqt")
    return request.getfixturevalue("qapp")


def _draw(data_or_path, size=48) -> np.ndarray:
    """(size, size, 4) RGBA picture of an SVG drawn by Qt on a transparent image."""
    from PySide6.QtCore import QByteArray, QRectF
    from PySide6.QtGui import QImage, QPainter
    from PySide6.QtSvg import QSvgRenderer

    arg = QByteArray(data_or_path) if isinstance(data_or_path, bytes) else str(data_or_path)
    renderer = QSvgRenderer(arg)
    assert renderer.isValid()
    img = QImage(size, size, QImage.Format.Format_RGBA8888)
    img.fill(0)
    painter = QPainter(img)
    renderer.render(painter, QRectF(0, 0, size, size))
    painter.end()
    return np.frombuffer(img.constBits(), np.uint8).reshape(size, size, 4).copy()


@pytest.mark.parametrize("name", res.ICONS)
def test_qt_draws_every_icon(qt_app, name):
    from PySide6.QtGui import QIcon

    rgba = _draw(res.icon_path(name))
    ink = rgba[..., 3] > 64
    assert 0.06 < ink.mean() < (0.95 if name == res.APP_ICON else 0.6), ink.mean()
    rows, cols = np.nonzero(ink)  # drawn over most of the square, not in a corner
    assert np.ptp(rows) > 30 and np.ptp(cols) > 30
    assert not QIcon(str(res.icon_path(name))).pixmap(24, 24).isNull()
    if name in res.TOOLBAR_ICONS:  # the strokes follow the root colour (themes)
        red = _draw(res.icon_svg(name, "#ff0000"))
        is_red = (red[..., 0] > 200) & (red[..., 1] < 60) & (red[..., 3] > 200)
        assert is_red.sum() > 40


# -- example sessions --------------------------------------------------------------------


def test_example_sessions_are_listed():
    examples = res.example_sessions()
    assert set(REQUIRED_SESSIONS) <= set(examples)
    assert all(p.suffix == ".svs" and p.is_file() for p in examples.values())
    assert res.default_session() == examples[res.DEFAULT_SESSION]
    with pytest.raises(res.ResourceError, match="'nope'.*examples: .*marschner-lobb"):
        res.example_session("nope")


def _corners_in_view(camera, bounds, aspect: float) -> np.ndarray:
    """Normalised device (x, y) of the 8 corners of ``bounds`` seen by ``camera`` (VTK
    conventions: vertical view angle) in a window of width/height ``aspect``."""
    pos = np.asarray(camera.position, float)
    fwd = np.subtract(camera.focal_point, pos)
    fwd /= np.linalg.norm(fwd)
    up = np.asarray(camera.view_up, float)
    up = up - up.dot(fwd) * fwd
    up /= np.linalg.norm(up)
    right = np.cross(fwd, up)
    corners = np.array([[x, y, z] for x in bounds[0] for y in bounds[1] for z in bounds[2]])
    rel = corners - pos
    depth = rel @ fwd
    assert (depth > 0).all()  # all in front of the camera
    t = np.tan(np.radians(camera.view_angle) / 2)
    return np.stack([rel @ right / (depth * t * aspect), rel @ up / (depth * t)], axis=1)


@pytest.fixture(scope="module")
def loaded():
    """name -> Scene of every example session (loaded once)."""
    from splineviz.model.session import load_scene

    return {name: load_scene(path) for name, path in res.example_sessions().items()}


@pytest.mark.parametrize("name", sorted(res.example_sessions()))
def test_example_session_is_synthetic_and_as_the_app_writes_it(loaded, name):
    from splineviz.model import VolumeNode
    from splineviz.model.session import to_session

    scene = loaded[name]
    assert scene.volumes and scene.isosurfaces
    for node in scene:  # sources of the plugin only: no data file is shipped
        assert getattr(node, "path", None) is None
        if isinstance(node, VolumeNode):
            assert node.source is not None
    doc = json.loads(res.example_session(name).read_text(encoding="utf-8"))
    written = to_session(scene).to_document()
    assert written["objects"] == doc["objects"] and written["views"] == doc["views"]


@pytest.mark.parametrize("name", sorted(res.example_sessions()))
@pytest.mark.parametrize("aspect", [1.0, 4 / 3, 16 / 9])
def test_example_camera_shows_the_whole_data_box(loaded, name, aspect):
    scene = loaded[name]
    ndc = _corners_in_view(scene.camera, scene.bounds(), aspect)
    assert np.abs(ndc).max() < 0.95, ndc  # with a margin for the axes labels


@pytest.mark.parametrize("name", sorted(res.example_sessions()))
def test_example_session_renders(loaded, name):
    from splineviz.render.scene_view import render_scene

    scene = loaded[name]
    img = np.asarray(render_scene(scene, size=SIZE))[..., :3].astype(int)
    assert img.shape == (SIZE[1], SIZE[0], 3)
    background = np.rint(np.asarray(scene.view.background) * 255)
    differs = np.abs(img - background).sum(axis=2) > 30
    assert differs.mean() > 0.05
    # isosurfaces are coloured; background, outlines and labels are grey
    coloured = (img.max(axis=2) - img.min(axis=2)) > 40
    assert coloured.mean() > 0.02, coloured.mean()
    # nothing of the data is cut at the borders of the picture
    assert not coloured[[0, -1], :].any() and not coloured[:, [0, -1]].any()
