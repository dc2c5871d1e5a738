"""File > Open of an OME-Zarr folder in the GUI: the chunked volume renders in bricks on dask
workers through the model's opening path (issue 15; 1024^3 under -m slow)."""

import pytest

pytest.importorskip("pytestqt")

from splineviz.gui.main_window import MainWindow  # noqa: E402

SIZE = (160, 120)


@pytest.fixture
def window(qtbot, tmp_path):
    from PySide6.QtCore import QSettings

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope, str(tmp_path))
    w = MainWindow(size=SIZE)
    qtbot.addWidget(w)
    w.resize(900, 560)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.wait_idle()
    w.close()


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
