"""Bricked, out-of-core ray casting on dask workers gives the single ray caster's picture
(issue 15): bonsai in 8 bricks on a LocalCluster of 2 workers, every model, opaque and
translucent, with and without a clip plane; empty and hidden bricks skipped exactly;
cancellation."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.compute.bricked import BrickedRayCaster
from splineviz.core.camera import default_camera
from splineviz.core.splines import MODELS

from .bricked_helpers import assert_same_picture, compare_frames, local_client
from .helpers import HAVE_CL

pytestmark = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")

#: bonsai's isovalue of the tests (the trunk and the leaves). Not an integer: at 40 the
#: uint8 samples equal the isovalue on whole patches of the data box's faces, where the
#: first root sits exactly at the ray's entry point and float32 rounding decides whether it
#: is found (the bricks compute the single cast's floats, so they agree there too, but the
#: picture would test rounding rather than surfaces)
ISO = 40.5
#: the models with a kernel (a plugin's global spline cannot be cut into bricks)
KERNEL_MODELS = [m for m, spec in MODELS.items() if spec.family is not None]


@pytest.fixture(scope="module")
def bonsai(shared_data):
    return sv.read_volume(shared_data / "volumes" / "bonsai.vti")


@pytest.fixture(scope="module")
def client():
    with local_client(workers=2, processes=False) as c:
        yield c


def _clip(vol):
    centre = np.asarray(vol.bounds).mean(axis=1)
    return [(centre + (10, 0, 0), (-1.0, 0.3, 0.2))]


@pytest.mark.parametrize("model", KERNEL_MODELS)
def test_bonsai_in_8_bricks_is_the_single_picture(bonsai, client, model):
    """Every model, with and without a clip plane, opaque (least depth) and translucent
    (painted back to front): depth within 1e-6 on every pixel both hit (the bricks compute
    the single cast's floats: in fact equal), hit masks and colours as the single cast's."""
    cam = default_camera(bonsai.bounds)
    rc = sv.RayCaster(bonsai, model=model)
    rc.set_isovalue(ISO)
    brc = BrickedRayCaster(bonsai, model=model, client=client, bricks=2)
    brc.set_isovalue(ISO)
    for planes in ((), _clip(bonsai)):
        single = rc.render(cam, (96, 72), clip_planes=planes)
        for composite in ("nearest", "back-to-front"):
            bricked = brc.render(cam, (96, 72), clip_planes=planes, composite=composite)
            assert brc.stats["bricks"] == 8
            assert brc.stats["bricks_rendered"] + brc.stats["bricks_culled"] == 8
            # each brick casts its footprint only, not the frame
            assert all(t["pixels"] < 96 * 72 for t in brc.stats["brick_times"])
            assert_same_picture(compare_frames(single, bricked, opacity=0.4))


def test_hidden_and_empty_bricks_are_skipped_exactly(bonsai, client):
    # a view straight down the x axis of a solid block: the front bricks hide the back ones
    block = sv.Volume(np.pad(np.ones((40, 40, 40), np.float32), 1), spacing=(1, 1, 1))
    cam = sv.Camera((-80, 20.3, 20.7), (20, 20.3, 20.7), view_up=(0, 0, 1))
    rc = sv.RayCaster(block, model="trilinear")
    rc.set_isovalue(0.5)
    single = rc.render(cam, (48, 40))
    brc = BrickedRayCaster(block, model="trilinear", client=client, bricks=2)
    brc.set_isovalue(0.5)
    assert_same_picture(compare_frames(single, brc.render(cam, (48, 40))))
    assert brc.stats["bricks_culled"] == 4  # the back half, never read
    # bounds reported by the rendered bricks skip them unread at an isovalue outside; the
    # hidden ones were never read, so they are rendered (and found empty) now
    brc.set_isovalue(2.0)
    frame = brc.render(cam, (48, 40))
    assert not frame.hit.any()
    assert brc.stats["bricks_empty"] == 4 and brc.stats["bricks_rendered"] == 4
    brc.set_isovalue(3.0)
    brc.render(cam, (48, 40))
    assert brc.stats["bricks_empty"] == 8 and brc.stats["bricks_rendered"] == 0
    # one pass of summaries (dask min/max on the workers) knows every brick at once
    fresh = BrickedRayCaster(block, model="cubic-c1", client=client, bricks=2)
    bounds = fresh.summarize()
    assert len(bounds) == 8 and all(lo <= 0.0 and hi >= 1.0 for lo, hi in bounds.values())
    fresh.set_isovalue(-1000.0)  # the bounds widen by ghosts and negative weights
    assert not fresh.render(cam, (48, 40)).hit.any()
    assert fresh.stats["bricks_empty"] == 8


def test_frames_preview_first_and_cancel(bonsai, client):
    import dask.array as da

    from splineviz.core.chunked import ChunkedVolume, coarsen_level

    data = da.from_array(bonsai.data, chunks=64)
    full = ChunkedVolume(data, bonsai.spacing, bonsai.origin)
    vol = ChunkedVolume(data, bonsai.spacing, bonsai.origin,
                        levels=(coarsen_level(full.all_levels()[0], 40**3),))
    brc = BrickedRayCaster(vol, model="trilinear", client=client, bricks=2)
    brc.set_isovalue(ISO)
    cam = default_camera(vol.bounds)
    stages = [(s, d, t) for s, d, t, _ in brc.frames(cam, (64, 48))]
    assert stages[0][0] == "preview" and stages[-1][0] == "exact"
    assert [d for s, d, _ in stages if s == "bricks"] == sorted(
        d for s, d, _ in stages if s == "bricks")
    # closing the generator after the preview cancels the bricks sent so far
    gen = brc.frames(cam, (64, 48))
    assert next(gen)[0] == "preview"
    next(gen)
    gen.close()
    assert brc._pending == []


def test_a_dask_array_from_python_renders(client):
    import dask.array as da

    f = sv.testfunctions.TEST_FUNCTIONS["ml"]
    small = sv.Volume.from_function(f, (33, 33, 33), f.domain)
    vol = sv.Volume.from_dask(da.from_array(small.data, chunks=16), small.spacing,
                              small.origin)
    assert vol.shape == (33, 33, 33) and vol.chunks == (16, 16, 16)
    cam = default_camera(vol.bounds)
    rc = sv.RayCaster(small, model="to-quadratic")
    rc.set_isovalue(f.isovalue)
    brc = BrickedRayCaster(vol, model="to-quadratic", client=client, brick_size=16)
    assert brc.stats["bricks"] == 8
    brc.set_isovalue(f.isovalue)
    assert_same_picture(compare_frames(rc.render(cam, (64, 48)), brc.render(cam, (64, 48))))


def test_models_without_a_kernel_are_refused(monkeypatch):
    """A plugin model declares no reach of its stencils (the tricubic B-spline interpolant
    reads the whole volume through its prefilter): bricks cannot carry its spline."""
    from splineviz.compute.raycast import RayCastError
    from splineviz.core.splines import MODELS, ModelSpec

    monkeypatch.setitem(MODELS, "global-model", ModelSpec("global-model", "m:C"))
    with pytest.raises(RayCastError, match="cannot be rendered in bricks"):
        BrickedRayCaster(np.zeros((4, 4, 4), np.float32), model="global-model")


def test_a_layer_of_a_chunked_volume_reports_bricks_and_gives_up_old_views(bonsai, client,
                                                                          monkeypatch):
    import dask.array as da

    from splineviz.compute import bricked
    from splineviz.core.chunked import ChunkedVolume
    from splineviz.render.isosurface import IsosurfaceLayer, ViewState

    monkeypatch.setattr(bricked, "BRICK_CELLS", 128)  # 8 bricks of bonsai
    saved = dict(bricked.DEFAULTS)
    bricked.configure(scheduler=client.scheduler.address)
    try:
        vol = ChunkedVolume(da.from_array(bonsai.data, chunks=128), bonsai.spacing,
                            bonsai.origin)
        layer = IsosurfaceLayer(vol, model="trilinear", isovalue=ISO)
        view = ViewState(default_camera(vol.bounds), (64, 48))
        seen = []
        rf = layer.compute(view, progress=lambda done, total: seen.append((done, total)))
        assert rf.path == "bricked" and rf.final and rf.frame.hit.any()
        assert seen[-1] == (8, 8) and len(seen) >= 2
        # a camera that moved on: the frame is given up, its bricks cancelled
        assert layer.compute(view, cancelled=lambda: True) is None
        # previews while the camera moves: the coarse level, ray cast here
        pre = layer.compute(view, scale=0.5, preview=True)
        assert pre.path == "preview" and pre.frame.hit.any()
    finally:
        bricked.close_clients()
        bricked.configure(**saved)
