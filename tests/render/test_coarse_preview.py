"""A chunked volume shows its coarse level first (issue 26, item 5): an OME-Zarr opened through
the real reader is ray cast from its pyramid level (or, without a pyramid, a strided
downsample) at once, and the exact bricked frame follows and replaces it."""

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from compute.bricked_helpers import write_ball_ome_zarr  # noqa: E402
from compute.helpers import HAVE_CL  # noqa: E402

import splineviz as sv  # noqa: E402
from splineviz.core.chunked import ChunkedVolume  # noqa: E402
from splineviz.render.isosurface import IsosurfaceLayer  # noqa: E402
from splineviz.render.overlay import shown_description  # noqa: E402
from splineviz.render.scene import SplineScene  # noqa: E402

pytestmark = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")

#: 160^3 samples in chunks of 40, levels of 80^3 and 40^3: the 80^3 level is the finest within
#: the preview budget (128^3 samples)
N, CHUNK = 160, 40
SIZE = (96, 72)
ISO = 100.0


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return write_ball_ome_zarr(tmp_path_factory.mktemp("coarse") / "ball.ome.zarr", N, CHUNK)


@pytest.fixture
def bricks_in_process():
    """Bricks rendered by an in-process LocalCluster (no worker processes to start)."""
    from distributed import LocalCluster

    from splineviz.compute import bricked

    saved = dict(bricked.DEFAULTS)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        bricked.configure(scheduler=cluster.scheduler_address)
        try:
            yield
        finally:
            bricked.close_clients()
            bricked.configure(**saved)


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / max((a | b).sum(), 1))


def _frames_on_the_way(vol):
    """(frames shown on the way, exact results, scene, layer, plotter) of a progressive scene
    of ``vol`` refined as the window's worker refines it."""
    pl = pv.Plotter(off_screen=True, window_size=SIZE)
    scene = SplineScene(pl, progressive=True)
    layer = IsosurfaceLayer(vol, model="cubic-c1", isovalue=ISO)
    scene.add_layer(layer)
    pl.camera_position = [(500.0, -380.0, 300.0), (80.0, 80.0, 80.0), (0.0, 0.0, 1.0)]
    pl.camera_set = True
    pl.render_window.Render()  # the GUI thread's render: no caster yet, nothing shown
    assert scene.shown_frame(layer) is None and scene.needs_refine()
    partial = []
    results = scene.refine(partial=lambda lyr, rf: partial.append(rf))
    return partial, results, scene, layer, pl


def test_the_first_frame_comes_from_the_pyramid_and_the_exact_one_replaces_it(
        store, bricks_in_process):
    vol = sv.read_volume(store)
    assert isinstance(vol, ChunkedVolume) and [lv.shape for lv in vol.levels] == [
        (80, 80, 80), (40, 40, 40)]
    partial, results, scene, layer, pl = _frames_on_the_way(vol)
    try:
        assert partial, "no frame before the exact one"
        first = partial[0]
        assert first.path == "preview" and not first.final
        assert first.source == "coarse level 1 of 2 (80^3 of 160^3)"
        # the preview shown while the bricks are cast is of full resolution
        sharp = partial[-1]
        assert sharp.path == "preview" and sharp.scale == 1.0
        assert "on coarse level 1 of 2" in shown_description(layer, sharp)
        [(lyr, exact)] = results
        assert lyr is layer and exact.final and exact.path == "bricked" and exact.source == ""
        assert exact.frame.hit.mean() > 0.05
        # the coarse picture is the exact one's, up to the level's resolution
        assert _iou(sharp.frame.hit, exact.frame.hit) > 0.9
        scene.apply([(layer, sharp)])
        assert scene.shown_frame(layer) is sharp
        assert scene.apply(results) and scene.shown_frame(layer) is exact
        assert not scene.needs_refine()
    finally:
        pl.close()


def test_without_a_pyramid_a_strided_downsample_previews(store, bricks_in_process):
    # the full level's own folder: a plain Zarr array, no multiscales
    vol = sv.read_volume(store / "s0")
    assert isinstance(vol, ChunkedVolume) and vol.levels == ()
    partial, results, _scene, _layer, pl = _frames_on_the_way(vol)
    try:
        assert partial[0].source == "downsample 1:2 (80^3 of 160^3)"
        [(_, exact)] = results
        assert exact.final and exact.path == "bricked"
        assert _iou(partial[-1].frame.hit, exact.frame.hit) > 0.9
    finally:
        pl.close()
