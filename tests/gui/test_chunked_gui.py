"""File > Open of an OME-Zarr folder in the GUI: the chunked volume renders in bricks on dask
workers through the model's opening path (issue 15; 1024^3 under -m slow)."""

import pytest

pytest.importorskip("pytestqt")


SIZE = (160, 120)




@pytest.fixture
def bricks_on(request):
    """Bricks of the GUI's layers rendered by ``request.param``: an in-process LocalCluster
    (its scheduler address, as ``--scheduler`` gives one) or None (the app's own
    LocalCluster of worker processes)."""
    from compute.helpers import HAVE_CL

    from splineviz.compute import bricked

    if not HAVE_CL:
        pytest.skip("no OpenCL device")
    saved = dict(bricked.DEFAULTS)
    if request.param == "inproc":
        from distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                          dashboard_address=":0") as cluster:
            bricked.configure(scheduler=cluster.scheduler_address)
            yield
            bricked.close_clients()
    else:
        yield
        bricked.close_clients()
    bricked.configure(**saved)


def _open_and_render(window, path):
    from splineviz.core.chunked import ChunkedVolume

    window.open_path(path, mode="replace", block=True)
    node = window.scene.volumes[0]
    assert isinstance(node.data, ChunkedVolume)
    iso = window.scene.isosurfaces[0]
    iso.isovalue = 100.0
    window.wait_for_refine(timeout_s=600)
    rf = window.spline_scene.shown_frame(window.view.scene_view.layers[iso.id])
    assert rf.final and rf.path == "bricked"
    assert rf.frame.hit.mean() > 0.05
    return rf


@pytest.mark.parametrize("bricks_on", ["inproc"], indirect=True)
def test_small_ome_zarr_opens_and_renders(window, tmp_path, bricks_on):
    from compute.bricked_helpers import write_ball_ome_zarr

    path = write_ball_ome_zarr(tmp_path / "ball.ome.zarr", 64, 16)
    rf = _open_and_render(window, path)
    assert rf.stats["bricks"] >= 1


@pytest.mark.slow
@pytest.mark.parametrize("bricks_on", ["local"], indirect=True)
def test_1024_cubed_ome_zarr_opens_and_renders(window, tmp_path, bricks_on):
    from compute.bricked_helpers import write_ball_ome_zarr

    path = write_ball_ome_zarr(tmp_path / "ball.ome.zarr", 1024, 128)
    rf = _open_and_render(window, path)
    print(f"GUI, 1024^3 OME-Zarr: exact frame {rf.seconds:.1f} s, bricks "
          f"{rf.stats['bricks']} rendered {rf.stats['bricks_rendered']} culled "
          f"{rf.stats['bricks_culled']}")


@pytest.mark.parametrize("bricks_on", ["inproc"], indirect=True)
def test_the_coarse_level_shows_while_the_bricks_compute(window, tmp_path, bricks_on):
    """Issue 26, item 5: the view is not empty while the exact bricks are computed — the
    pyramid level within the preview budget is shown first, at full size, and named; the
    exact bricked frame replaces it; a new isovalue previews through that level at once."""
    from compute.bricked_helpers import write_ball_ome_zarr
    from PySide6.QtWidgets import QApplication

    path = write_ball_ome_zarr(tmp_path / "ball.ome.zarr", 160, 40)
    shown = []  # (frame, refining, quad shows an image) after each render of a new frame

    def record(_seconds):
        scene = window.spline_scene
        if scene is None or not scene.layers:
            return
        layer = scene.layers[0]
        rf = scene.shown_frame(layer)
        if rf is not None and (not shown or shown[-1][0] is not rf):
            shown.append((rf, window.view.refining, scene.quad(layer).has_image))

    window.view.frame_rendered.connect(record)
    window.open_path(path, mode="replace", block=True)
    iso = window.scene.isosurfaces[0]
    iso.isovalue = 100.0
    window.wait_for_refine(timeout_s=600)
    layer = window.view.scene_view.layers[iso.id]
    current = [(rf, busy, image) for rf, busy, image in shown if rf.state == layer.state]
    *before, (exact, _, _) = current
    assert exact.final and exact.path == "bricked"
    assert before, "nothing shown before the exact frame"
    for rf, _, _ in before:
        assert rf.path == "preview" and rf.source == "coarse level 1 of 2 (80^3 of 160^3)"
    sharp = [rf for rf, busy, image in before
             if busy and image and rf.scale == 1.0 and rf.frame.hit.mean() > 0.05]
    assert sharp, "no full-size coarse picture while the bricks were computed"

    # a new isovalue: the GUI thread's own preview, from the coarse level, before any brick
    iso.isovalue = 120.0
    for _ in range(20000):
        QApplication.processEvents()
        rf = window.spline_scene.shown_frame(layer)
        if rf.state == layer.state:
            break
    assert rf.state == layer.state and rf.path == "preview"
    assert rf.source.startswith("coarse level 1 of 2") and rf.frame.hit.any()
    window.wait_for_refine(timeout_s=600)
    assert window.spline_scene.shown_frame(layer).path == "bricked"
