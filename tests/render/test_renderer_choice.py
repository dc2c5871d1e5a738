"""The renderer choice of an isosurface (issue 32, part 3): ray casting or cell projection,
chosen per node, kept in sessions, on the command line, and drawn by ``render_scene``.

Pictures of the two renderers are compared by :mod:`renderer_agreement` (masks, colours and
window depth away from silhouettes); ``-s`` prints the figures.
"""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from renderer_agreement import agreement, scene_picture

from splineviz.cli import main
from splineviz.core.renderers import (
    CELL_PROJECTION,
    RAY_CASTING,
    RENDERERS,
    choose_renderer,
    renderer_name,
)
from splineviz.model import IsosurfaceNode
from splineviz.model.nodes import ModelError
from splineviz.model.opening import default_scene
from splineviz.resources import example_session

SIZE = (200, 150)
SESSION = example_session("marschner-lobb")


def _bare_default_scene(renderer):
    """The embedded default data (Marschner-Lobb, cubic C1) without outline and axes."""
    scene = default_scene()
    for vol in scene.volumes:
        vol.show_outline = False
    scene.view.show_scale = False
    scene.isosurfaces[0].renderer = renderer
    return scene


def test_the_choice_follows_the_machine_and_the_model():
    assert choose_renderer("auto", "cubic-c1", opencl=True).renderer == RAY_CASTING
    assert choose_renderer("auto", "cubic-c1", opencl=False) == choose_renderer(
        "cell-projection", "super-quadratic")
    assert choose_renderer("auto", "cubic-c1", opencl=False).renderer == CELL_PROJECTION
    # what cell projection does not draw is ray cast, and the note says why in a sentence
    assert choose_renderer("cell-projection", "to-quadratic").renderer == CELL_PROJECTION
    assert choose_renderer("auto", "to-quadratic", opencl=False).renderer == CELL_PROJECTION
    for args, why in ((("cell-projection", "trilinear"), "'trilinear' is ray cast"),
                      (("cell-projection", "cubic-c1", "mean-curvature"), "colour by"),
                      (("cell-projection", "cubic-c1", "none", True, "an oblique scan"),
                       "oblique"),
                      (("auto", "trilinear", "none", False), "slow NumPy")):
        choice = choose_renderer(*args)
        assert choice.renderer == RAY_CASTING and why in choice.note
        assert "\n" not in choice.note
    assert choose_renderer("raycast", "cubic-c1", opencl=False).renderer == RAY_CASTING


def test_a_node_takes_the_names_and_refuses_others_in_one_sentence():
    node = IsosurfaceNode(isovalue=1.0)
    assert node.renderer == "auto" and "renderer" not in node.state()
    node.renderer = "raycast"  # the spelling of the key
    assert node.renderer == "ray-casting" == renderer_name("ray-cast")
    with pytest.raises(ModelError, match="unknown renderer 'opengl'; choose one of auto"):
        node.renderer = "opengl"
    assert node.renderer == "ray-casting"
    assert list(RENDERERS) == ["auto", "ray-casting", "cell-projection"]
    assert RENDERERS["cell-projection"].label == "cell projection (OpenGL)"


def test_sessions_keep_the_renderer_and_old_ones_load_as_auto(tmp_path):
    from splineviz.model.session import load_scene, save_scene

    scene = default_scene()
    scene.isosurfaces[0].renderer = "cell-projection"
    path = save_scene(scene, tmp_path / "cp.svs")
    doc = json.loads(path.read_text())
    iso = next(o for o in doc["objects"] if o["type"] == "Isosurface")
    assert iso["properties"]["renderer"] == "cell-projection"
    assert load_scene(path).isosurfaces[0].renderer == "cell-projection"
    # the default is not written: a session saved before the property existed is the same
    scene.isosurfaces[0].renderer = "auto"
    text = save_scene(scene, tmp_path / "auto.svs").read_text()
    assert "renderer" not in text
    assert load_scene(SESSION).isosurfaces[0].renderer == "auto"
    iso["properties"]["renderer"] = "vulkan"
    bad = tmp_path / "bad.svs"
    bad.write_text(json.dumps(doc))
    with pytest.raises(Exception, match="unknown renderer 'vulkan'"):
        load_scene(bad)


def test_render_flag_and_its_one_sentence_error(tmp_path, capsys):
    out = tmp_path / "cp.png"
    assert main(["render", str(SESSION), "--size", "64x48", "--renderer", "cell-projection",
                 "-o", str(out)]) == 0
    assert out.exists() and capsys.readouterr().out.strip().endswith("cell-projection")
    # a model cell projection does not draw: ray cast, with a note on stderr
    assert main(["render", str(SESSION), "--size", "64x48", "--renderer", "cell-projection",
                 "--model", "trilinear", "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip().endswith("ray-casting")
    assert "'trilinear' is ray cast" in captured.err
    rc = main(["render", str(SESSION), "--renderer", "opengl", "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1
    assert "unknown renderer 'opengl'; choose one of auto, ray-casting, cell-projection" in err


def test_movie_and_the_apps_screenshot_take_the_renderer_flag(tmp_path, capsys, monkeypatch):
    from PIL import Image

    frames = tmp_path / "f_%02d.png"
    assert main(["movie", str(SESSION), "--size", "64x48", "--frames", "2", "--orbit", "20",
                 "--renderer", "cell-projection", "-o", str(frames)]) == 0
    still = tmp_path / "still.png"
    assert main(["render", str(SESSION), "--size", "64x48", "--renderer",
                 "cell-projection", "-o", str(still)]) == 0
    ray = tmp_path / "ray.png"
    assert main(["render", str(SESSION), "--size", "64x48", "--renderer", "ray-casting",
                 "-o", str(ray)]) == 0
    first, cells, cast = (np.asarray(Image.open(p)) for p in
                          (tmp_path / "f_00.png", still, ray))
    np.testing.assert_array_equal(first, cells)  # the movie's first frame: cell projected
    assert not np.array_equal(cells, cast)
    # the app's --screenshot without a display: the same picture
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    shot = tmp_path / "shot.png"
    capsys.readouterr()
    assert main([str(SESSION), "--renderer", "cell-projection", "--screenshot", str(shot),
                 "--size", "64x48"]) == 0
    from splineviz.model.opening import scene_from_path
    from splineviz.render.scene_view import render_scene

    np.testing.assert_array_equal(np.asarray(Image.open(shot)), render_scene(
        scene_from_path(SESSION, renderer="cell-projection"), (64, 48)))
    assert main(["movie", str(SESSION), "--renderer", "gl", "-o", str(frames)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "unknown renderer 'gl'" in err


#: hides every OpenCL platform from a process before splineviz looks for one: an ICD loader
#: that lists none, or one that fails as without any ICD installed
_NO_OPENCL = {
    "no platform": """
import pyopencl
pyopencl.get_platforms = lambda: []
""",
    "loader fails": """
import pyopencl

def _no_icd():
    raise pyopencl.LogicError("clGetPlatformIDs failed: PLATFORM_NOT_FOUND_KHR")

pyopencl.get_platforms = _no_icd
"""}


@pytest.mark.parametrize("hidden", list(_NO_OPENCL))
def test_without_opencl_the_default_data_is_cell_projected_as_the_ray_caster_draws_it(
        tmp_path, hidden):
    # a fresh interpreter: the device choice is cached per process
    script = _NO_OPENCL[hidden] + textwrap.dedent(f"""
        import sys, warnings
        import numpy as np
        sys.path.insert(0, {str(Path(__file__).parents[1])!r})
        from renderer_agreement import scene_picture
        from splineviz.compute.device import opencl_works
        from splineviz.cli import main
        from splineviz.model.opening import default_scene
        assert not opencl_works()
        scene = default_scene()
        for vol in scene.volumes:
            vol.show_outline = False
        scene.view.show_scale = False
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no "NumPy reference path" fallback warning
            colour, depth = scene_picture(scene, {SIZE!r})
        np.savez({str(tmp_path / "cp.npz")!r}, colour=colour, depth=depth)
        sys.exit(main(["render", {str(SESSION)!r}, "--size", "64x48", "-o",
                       {str(tmp_path / "cli.png")!r}]))
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().endswith("cell-projection")  # splineviz render chose it too
    assert (tmp_path / "cli.png").exists()
    cp = np.load(tmp_path / "cp.npz")
    ref = scene_picture(_bare_default_scene("ray-casting"), SIZE)
    figures = agreement(ref, (cp["colour"], cp["depth"]), ref[0][0, 0])
    print(f"no OpenCL ({hidden}), default data:", figures)
    assert figures.both > 1500 and figures.acceptable(), figures


def _plane_mesh(scene):
    v = np.array([[-1.2, -1.2, -0.3], [1.2, -1.2, 0.2], [1.2, 1.2, 0.3], [-1.2, 1.2, -0.2]])
    scene.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), name="plane", color=(0.2, 0.8, 0.3))


@pytest.mark.parametrize("case", ["clip plane", "mesh through it", "translucent",
                                  "translucent over a mesh"])
def test_the_scene_composes_cell_projection_as_the_ray_cast_frame(case):
    pictures = []
    for renderer in ("ray-casting", "cell-projection"):
        scene = _bare_default_scene(renderer)
        if case == "clip plane":
            scene.add_clip_plane((0.1, 0.0, 0.0), (-1.0, 0.3, 0.2))
        if "mesh" in case:
            _plane_mesh(scene)
        if "translucent" in case:
            scene.isosurfaces[0].opacity = 0.6
        pictures.append(scene_picture(scene, SIZE))
    figures = agreement(*pictures, pictures[0][0][0, 0])
    print(f"{case}:", figures)
    assert figures.both > 800 and figures.acceptable(), figures


def test_a_translucent_surface_blends_its_first_hit_only():
    # without the depth pre-pass every fold of the surface behind the first would blend in
    from splineviz.render.scene_view import OffscreenRenderer

    scene = _bare_default_scene("cell-projection")
    scene.isosurfaces[0].opacity = 0.6
    with OffscreenRenderer(scene, SIZE) as r:
        (pl, view), = r._views
        pl.render_window.SetMultiSamples(0)
        with_prepass = r.render()
        cells = view.spline_scene._views[id(view.layers[scene.isosurfaces[0].id])].cells
        cells.depth_actor.SetMapper(None)  # the colour pass alone
        cells.depth_actor.VisibilityOff()
        cells.set_visible = lambda _v: None
        without = r.render()
    ref_scene = _bare_default_scene("ray-casting")
    ref_scene.isosurfaces[0].opacity = 0.6
    ref = scene_picture(ref_scene, SIZE)
    bg = ref[0][0, 0]
    good = agreement(ref, (with_prepass, ref[1]), bg)
    bad = agreement(ref, (without, ref[1]), bg)
    print("translucent with / without the depth pre-pass:", good, "/", bad)
    assert good.colour_share >= 0.995 > bad.colour_share


def test_a_progressive_view_draws_the_tets_a_worker_made():
    # the GUI's way: the render before the tets exist shows nothing of the surface and asks
    # for a refine; refine (a worker) makes them, apply + the next render draws them
    import pyvista as pv

    from splineviz.render.scene_view import SceneView

    scene = _bare_default_scene("cell-projection")
    pl = pv.Plotter(off_screen=True, window_size=SIZE)
    view = SceneView(scene, pl, progressive=True)
    try:
        asked = []
        view.spline_scene.request_refine = lambda: asked.append(True)
        layer = view.layers[scene.isosurfaces[0].id]
        pl.render_window.Render()
        assert asked and not view.spline_scene.drawn_by_cells(layer)
        assert view.spline_scene.needs_refine()
        results = view.spline_scene.refine()
        assert view.spline_scene.apply(results)
        pl.render_window.Render()
        assert view.spline_scene.drawn_by_cells(layer)
        assert not view.spline_scene.needs_refine()
        scene.isosurfaces[0].isovalue = 0.45  # new tets: the old ones stay until made
        pl.render_window.Render()
        assert not view.spline_scene.drawn_by_cells(layer)
        assert view.spline_scene.needs_refine()
    finally:
        view.close()
        pl.close()


def test_a_slow_cell_projection_moves_as_its_stand_in_and_shows_the_frame_a_worker_drew():
    """The GUI's way where a cell-projected frame is over the preview budget (software
    OpenGL): the trilinear stand-in while the camera or the isovalue moves, then the exact
    frame drawn off the GUI thread, shown by the quad, the very picture of the exact render;
    a fast machine draws the tets in the window."""
    import pyvista as pv

    from splineviz.render.scene import PREVIEW_BUDGET_S
    from splineviz.render.scene_view import SceneView
    from splineviz.render.volume_rendering import window_depth

    scene = _bare_default_scene("cell-projection")
    iso = scene.isosurfaces[0]
    pl = pv.Plotter(off_screen=True, window_size=SIZE)
    pl.render_window.SetMultiSamples(0)
    view = SceneView(scene, pl, progressive=True)
    ss = view.spline_scene
    slow = 3 * PREVIEW_BUDGET_S  # whatever this machine's speed

    def refine():
        assert ss.needs_refine()
        assert ss.apply(ss.refine())
        assert ss.cells_seconds is not None  # the worker's frame was timed
        ss.cells_seconds = slow
        pl.render_window.Render()

    def picture():
        return np.asarray(pl.screenshot(return_img=True))[..., :3], window_depth(pl, *SIZE)

    try:
        ss.request_refine = lambda: None
        layer = view.layers[iso.id]
        lv = ss._views[id(layer)]
        pl.render_window.Render()
        refine()
        assert lv.cell_frames and lv.quad.actor.GetVisibility()
        assert not lv.cells.actor.GetVisibility() and not lv.proxy_shown
        assert ss.drawn_by_cells(layer) and not ss.needs_refine()
        exact = scene_picture(scene, SIZE)
        figures = agreement(exact, picture(), exact[0][0, 0])
        print("worker's frame against the exact render:", figures)
        assert figures.both > 1500 and figures.acceptable() and figures.depth_max == 0.0

        ss.set_interacting(True)
        pl.camera.Azimuth(20)
        pl.render_window.Render()
        assert lv.proxy_shown and lv.proxy.actor.GetVisibility()
        assert not lv.quad.actor.GetVisibility() and not lv.cells.actor.GetVisibility()
        moving = picture()[0]
        assert (moving != moving[0, 0]).any(axis=2).mean() > 0.05  # the stand-in shows
        iso.isovalue = 0.45  # dragged: its tets are not made, the stand-in is at once
        pl.render_window.Render()
        assert lv.proxy_shown and lv.proxy.mesh is layer.cell_proxy(blocking=False)
        ss.set_interacting(False)  # released: the stand-in until the exact frame is drawn
        pl.render_window.Render()
        assert lv.proxy_shown and ss.needs_refine()
        refine()
        assert not lv.proxy_shown and lv.quad.actor.GetVisibility()
        assert not lv.proxy.actor.GetVisibility() and not ss.needs_refine()
        view.camera_from_vtk()  # the scene's camera is the one dragged
        exact = scene_picture(scene, SIZE)
        assert agreement(exact, picture(), exact[0][0, 0]).acceptable()

        ss.cells_seconds = 0.5 * PREVIEW_BUDGET_S  # fast: the tets drawn in the window
        pl.render_window.Render()
        assert not lv.cell_frames and lv.cells.actor.GetVisibility()
        assert not lv.quad.actor.GetVisibility() and not ss.needs_refine()
        ss.set_interacting(True)
        pl.camera.Azimuth(20)
        ss.cells_seconds = 0.5 * PREVIEW_BUDGET_S  # (the window's draw was timed)
        pl.render_window.Render()
        assert not lv.proxy_shown and lv.cells.actor.GetVisibility()
    finally:
        view.close()
        pl.close()


def test_more_clip_planes_than_cell_projection_takes_are_ray_cast(tmp_path, capsys):
    from splineviz.render.cell_projection import MAX_CLIP_PLANES
    from splineviz.render.scene_view import OffscreenRenderer

    scene = _bare_default_scene("cell-projection")
    for i in range(MAX_CLIP_PLANES + 1):
        scene.add_clip_plane((0.0, 0.0, -0.9 + 0.01 * i), (0.0, 0.0, 1.0))
    with OffscreenRenderer(scene, (48, 36)) as r:
        r.render()
        (_pl, view), = r._views
        layer = view.layers[scene.isosurfaces[0].id]
        assert view.spline_scene.renderer_of(layer) == RAY_CASTING
        assert not view.spline_scene.drawn_by_cells(layer)
        assert view.spline_scene.shown_frame(layer).final
    args = ["render", str(SESSION), "--size", "48x36", "--renderer", "cell-projection",
            "-o", str(tmp_path / "x.png")]
    for i in range(MAX_CLIP_PLANES + 1):
        args += ["--clip", f"0,0,{-0.9 + 0.01 * i},0,0,1"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert captured.out.strip().endswith("ray-casting")
    assert f"at most {MAX_CLIP_PLANES} clip planes" in captured.err
