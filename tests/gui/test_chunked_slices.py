"""Slice views of chunked volumes (issue 26, part 7): the worker reads the slab of samples
around a slice, never the whole store, and the slab's spline is the whole volume's on the
plane; the four-up layout on an OME-Zarr opened in the GUI shows the three slices with the
exact contour."""

import numpy as np
import pytest

from splineviz.core import slice_sampling
from splineviz.core.chunked import ChunkedVolume
from splineviz.core.splines import MODELS, build_spline
from splineviz.core.testfunctions import ml


class _Reads:
    """A region reader of an analytic field that records the boxes read."""

    def __init__(self, volume):
        self.volume, self.boxes = volume, []
        self.shape, self.dtype = volume.shape, volume.dtype

    def __getitem__(self, sl):
        self.boxes.append(tuple((s.start, s.stop) for s in sl))
        return self.volume.source[sl]


@pytest.fixture(scope="module")
def field():
    chunked = ChunkedVolume.from_function(ml, (24, 26, 28), ml.domain, chunks=8)
    whole = chunked.read([(0, n) for n in chunked.shape])
    return chunked, whole


@pytest.mark.parametrize("model", list(MODELS))
def test_the_slab_spline_is_the_whole_volume_spline_on_the_slice(field, model):
    from splineviz.gui.slice_worker import read_slab

    chunked, whole = field
    reference = build_spline(whole, model)
    for axis in range(3):
        lo, hi = whole.bounds[axis]
        # both faces, near them, between samples, an odd and an even sample
        for t in (0.0, 0.03, 0.21, 0.5, 0.77, 0.97, 1.0):
            pos = lo + t * (hi - lo)
            slab = read_slab(chunked, axis, pos, margin=2)
            assert slab.inner[0] <= pos <= slab.inner[1]
            assert slab.volume.shape[axis] <= 7 and slab.volume.shape[axis] < whole.shape[axis]
            grid = slice_sampling.slice_grid(whole.bounds, whole.spacing, axis, pos)
            got = slice_sampling.sample_slice(build_spline(slab.volume, model), grid)
            np.testing.assert_allclose(got, slice_sampling.sample_slice(reference, grid),
                                       rtol=0, atol=1e-12, err_msg=f"{model} axis {axis} {t}")


def test_only_the_slab_is_read_and_a_big_plane_comes_from_a_coarser_level(field):
    from dataclasses import replace

    from splineviz.gui.slice_worker import read_slab

    chunked, _ = field
    reads = _Reads(chunked)
    recorded = replace(chunked, source=reads, levels=(chunked.preview_level(12**3),),
                       _cache={})
    slab = read_slab(recorded, 2, recorded.bounds[2][0] + 10.3 * recorded.spacing[2], margin=4)
    assert reads.boxes == [((0, 24), (0, 26), (6, 16))]  # even start, the margin each side
    assert slab.volume.unit == recorded.unit
    coarse = recorded.levels[0]
    small = read_slab(recorded, 0, 0.0, max_samples=2000)
    assert len(reads.boxes) == 1  # not from the full level
    assert small.volume.spacing == pytest.approx(coarse.spacing)


# -- the GUI -------------------------------------------------------------------------------

ISO = 100.0


@pytest.fixture
def window(qapp, tmp_path):
    pytest.importorskip("pytestqt")
    pytest.importorskip("pyvistaqt")
    from compute.helpers import HAVE_CL
    from distributed import LocalCluster
    from interaction import pump
    from PySide6.QtCore import QSettings

    from splineviz.compute import bricked
    from splineviz.gui.main_window import MainWindow

    if not HAVE_CL:
        pytest.skip("no OpenCL device")
    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope,
                      str(tmp_path / "settings"))
    saved = dict(bricked.DEFAULTS)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        bricked.configure(scheduler=cluster.scheduler_address)
        w = MainWindow()
        w.show()
        for dock in w.docks.values():
            dock.hide()
        w.resize(900, 700)
        yield w
        w.wait_idle()
        w.close()
        pump(0.1)
        assert w.join_workers(30)
        bricked.close_clients()
    bricked.configure(**saved)


def test_four_up_on_an_ome_zarr_shows_the_slices_and_their_exact_contour(window, tmp_path):
    from compute.bricked_helpers import write_ball_ome_zarr
    from interaction import pump

    from splineviz.model.slices import AXES

    path = write_ball_ome_zarr(tmp_path / "ball.ome.zarr", 48, 16)
    window.open_path(path, mode="replace", block=True)
    node = window.scene.volumes[0]
    assert isinstance(node.data, ChunkedVolume)
    iso = window.scene.isosurfaces[0]
    iso.isovalue = ISO
    lay = window.view_layout
    lay.actions[("four-up", None)].trigger()
    assert pump(60, lambda: lay.ready)
    assert lay.slices.volume is node  # not refused for being chunked
    assert lay.slices.worker.wait(180) and pump(10, lambda: not lay.slices.rendering)
    # the reference: the spline of the whole store, read here for the comparison only
    whole = node.data.read([(0, n) for n in node.data.shape])
    spline = build_spline(whole, iso.model, **iso.model_options())
    lo, hi = whole.finite_range
    for name, view in lay.views.items():
        result = view.result
        assert result is not None, f"the {name} slice of the chunked volume is shown"
        assert result.grid.position == pytest.approx(lay.state.position(name))
        np.testing.assert_allclose(result.values, slice_sampling.sample_slice(spline,
                                                                              result.grid),
                                   rtol=0, atol=1e-9 * (hi - lo))
        assert result.curves, f"the {name} slice through the ball cuts its surface"
        pts = np.concatenate([c.points for c in result.curves])
        assert np.max(np.abs(spline.evaluate(pts) - ISO)) <= 1e-6 * (hi - lo)
        np.testing.assert_allclose(pts[:, AXES[name]], lay.state.position(name))
    # the next slice (the wheel's step) is read and shown too; the probe reads its spline
    before = lay.state.position("axial")
    lay.slices.scroll("axial", 3)
    assert lay.slices.worker.wait(120) and pump(10, lambda: not lay.slices.rendering)
    result = lay.views["axial"].result
    assert result.grid.position == pytest.approx(before + 3 * whole.spacing[2])
    point = result.grid.points()[len(result.grid.vs) // 2, len(result.grid.us) // 2]
    probe = lay.slices.probe(point)
    assert probe is not None and probe.value == pytest.approx(spline.evaluate(point[None])[0])
