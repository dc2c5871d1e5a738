"""A session round trip restores the same picture.

The scene of the issue (two isosurfaces of one volume, a clip plane on both, a point cloud)
is saved, loaded, saved again and loaded again; each isosurface is ray cast from the
restored session with the restored camera and clip planes and the frames are composited by
depth. The pictures of the original and the restored session must be identical, non-trivial,
and the clip plane must visibly change them (so it really came from the session). The GUI's
own screenshot of ``splineviz SESSION`` is compared once the GUI exists.
"""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.io import read_image
from splineviz.io.session import load_session, save_session

DATA = Path(__file__).resolve().parents[2] / ".." / "shared" / "data"
SIZE = (96, 72)


def _scene(folder: Path) -> Path:
    (folder / "data").mkdir()
    for suffix in (".mhd", ".raw"):
        shutil.copy(DATA / "volumes" / f"HeadMRVolume{suffix}", folder / "data")
    shutil.copy(DATA / "points" / "bunny_res2.ply", folder / "data")
    doc = {
        "format": "splineviz-session", "schema_version": 2,
        "objects": [
            {"id": "head", "type": "VolumeFile", "properties": {"path": "data/HeadMRVolume.mhd"}},
            {"id": "skin", "type": "Isosurface", "inputs": ["head"],
             "properties": {"isovalue": 40.0, "model": "trilinear", "color": [0.9, 0.7, 0.6],
                            "opacity": 0.5}},
            {"id": "bone", "type": "Isosurface", "inputs": ["head"],
             "properties": {"isovalue": 110.0, "model": "trilinear"}},
            {"id": "bunny", "type": "PointsFile", "properties": {"path": "data/bunny_res2.ply"}},
            {"id": "cut", "type": "ClipPlane", "inputs": ["skin", "bone"],
             "properties": {"origin": [94.0, 100.0, 82.0], "normal": [0.3, 1.0, 0.1]}},
        ],
        "views": [{"id": "view1", "type": "RenderView",
                   "camera": {"position": [420.0, -260.0, 230.0],
                              "focal_point": [94.0, 122.0, 82.0], "view_up": [0.0, 0.0, 1.0],
                              "view_angle": 35.0},
                   "background": [1.0, 1.0, 1.0]}],
    }
    (folder / "scene.svs").write_text(json.dumps(doc))
    return folder / "scene.svs"


def render(session, *, clip=True) -> np.ndarray:
    """Depth-composited (H, W, 3) picture of the session's visible isosurfaces."""
    view = session.views[0]
    cam = view.camera.to_camera()
    w, h = SIZE
    color = np.broadcast_to(np.asarray(view.background) * 255, (h, w, 3)).astype(np.float64)
    depth = np.ones((h, w))
    for obj in session.visible():
        if obj.type != "Isosurface":
            continue
        rc = sv.RayCaster(session.load_volume(obj.id), model=obj.properties.model)
        rc.set_isovalue(obj.properties.isovalue)
        planes = session.clip_planes_for(obj.id) if clip else ()
        frame = rc.render(cam, SIZE, clip_planes=planes)
        front = frame.hit & (frame.depth < depth)
        tint = frame.color[..., :3] * np.asarray(obj.properties.color)
        a = obj.properties.opacity
        color[front] = a * tint[front] + (1 - a) * color[front]
        depth[front] = frame.depth[front]
    return np.round(color).astype(np.uint8)


@pytest.mark.skipif(not DATA.is_dir(), reason="shared data sets not present")
def test_round_trip_restores_the_same_picture(tmp_path):
    src = _scene(tmp_path)
    original = load_session(src)
    (tmp_path / "saved").mkdir()
    save_session(original, tmp_path / "saved" / "copy.svs")  # another folder: paths rewritten
    # the copy names ../data: outside its folder, so read with the explicit opt-in
    restored = load_session(tmp_path / "saved" / "copy.svs", allow_outside=True)
    assert len(restored.load_points("bunny")) == 8171
    before, after = render(original), render(restored)
    np.testing.assert_array_equal(before, after)
    sv.write_screenshot(tmp_path / "before.png", before)
    np.testing.assert_array_equal(read_image(tmp_path / "before.png")[..., :3], after)
    background = np.all(before == 255, axis=2)
    assert 0.05 < 1 - background.mean() < 0.95  # something drawn, not everything
    unclipped = render(restored, clip=False)
    assert np.mean(np.any(unclipped != after, axis=2)) > 0.01  # the plane cut the picture
