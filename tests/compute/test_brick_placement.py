"""A brick ray cast in place (``RayCaster.render(placement=, window=)``) computes the single
cast's floats: bricks of a volume, each cast over its screen footprint in the whole volume's
coordinates and composited by least depth, give the single ray caster's frame bit for bit
(issue 15's exact depth compositing, without dask)."""

from dataclasses import replace

import numpy as np
import pytest

from splineviz.compute.raycast import RayCaster, RayCastError
from splineviz.core.bricks import BrickGrid, screen_footprint
from splineviz.core.camera import Camera
from splineviz.core.compositing import Composite, Fragment
from splineviz.core.splines import MODELS
from splineviz.core.volume import Volume

from .helpers import HAVE_CL, cameras, marschner_lobb

KERNEL_MODELS = [m for m, spec in MODELS.items() if spec.family is not None]
SIZE = (96, 72)


def _views(vol):
    """Two cameras outside the box, one inside it (its bricks reach behind the eye), and a
    clip plane on the second."""
    b = np.asarray(vol.bounds)
    c = b.mean(axis=1)
    outside = cameras(vol)[:2]
    inside = Camera(tuple(c + 0.11 * (b[:, 1] - b[:, 0])), tuple(c + (-3.0, 2.0, 1.0)),
                    view_angle=70.0)
    plane = [(tuple(c), (-1.0, 0.3, 0.2))]
    return [(outside[0], ()), (outside[1], plane), (inside, ())]


def _bricked(vol, model, iso, cam, planes, counts, spec_kwargs=None, device=None):
    """The frame of ``vol`` in ``counts`` bricks, each a ray caster of its read box cast in
    place over its footprint, composited by least depth."""
    spec = MODELS[model]
    grid = BrickGrid.split(vol.shape, counts, spec.ghost_layers, spec.lattice_period,
                           spec.centred_cells)
    clip = cam.fit_clipping_range(vol.bounds)
    cam = Camera(cam.position, cam.focal_point, cam.view_up, cam.view_angle, clip)
    comp = Composite(SIZE)
    for brick in grid:
        sl = tuple(slice(a, b) for a, b in brick.read)
        sub = Volume(vol.data[sl], vol.spacing, tuple(
            o + a * s for o, (a, _), s in zip(vol.origin, brick.read, vol.spacing, strict=True)))
        rc = RayCaster(sub, model=model, device=device, **(spec_kwargs or {}))
        rc.set_isovalue(iso)
        rect = screen_footprint(cam, grid.world_box(brick, vol.spacing, vol.origin), SIZE,
                                clip)[0]
        frame = rc.render(cam, SIZE, clip_planes=planes, window=rect,
                          placement=grid.placement(brick, vol.origin))
        assert frame.hit.shape == (rect[1] - rect[0], rect[3] - rect[2])
        comp.add_nearest(Fragment.from_frame(brick.index, frame, offset=(rect[0], rect[2])))
    return comp.frame()


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")
@pytest.mark.parametrize("model", KERNEL_MODELS)
def test_bricks_cast_in_place_are_the_single_cast_bit_for_bit(model):
    vol, iso = marschner_lobb(33)
    rc = RayCaster(vol, model=model)
    rc.set_isovalue(iso)
    for cam, planes in _views(vol):
        single = rc.render(cam, SIZE, clip_planes=planes)
        assert single.hit.sum() > 500
        # 3 x 2 x 2 bricks of 10-11 x 16 x 16 cells: offsets that are no powers of two
        frame = _bricked(vol, model, iso, cam, planes, (3, 2, 2))
        np.testing.assert_array_equal(frame.hit, single.hit)
        np.testing.assert_array_equal(frame.depth, single.depth)
        np.testing.assert_array_equal(frame.color, single.color)
        np.testing.assert_array_equal(frame.position, single.position)
        np.testing.assert_array_equal(frame.normal, single.normal)


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")
def test_a_window_casts_the_frames_own_pixels():
    vol, iso = marschner_lobb(17)
    rc = RayCaster(vol, model="cubic-c1")
    rc.set_isovalue(iso)
    cam = cameras(vol)[0]
    full = rc.render(cam, SIZE, hessian=True)
    win = rc.render(cam, SIZE, hessian=True, window=(11, 50, 7, 90))
    for name in ("hit", "depth", "color", "position", "normal", "hessian", "gradient_norm"):
        np.testing.assert_array_equal(getattr(win, name),
                                      getattr(full, name)[11:50, 7:90], err_msg=name)
    empty = rc.render(cam, SIZE, window=(20, 20, 0, 96))
    assert empty.hit.shape == (0, 96) and empty.depth.shape == (0, 96)
    with pytest.raises(RayCastError, match="not inside"):
        rc.render(cam, SIZE, window=(0, 73, 0, 96))


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")
def test_a_placement_must_fit_the_casters_samples_and_cells():
    vol, iso = marschner_lobb(17)
    grid = BrickGrid.split(vol.shape, 2, 1, 1, centred=True)
    brick = grid[(1, 0, 0)]
    sub = Volume(vol.data[tuple(slice(a, b) for a, b in brick.read)], vol.spacing)
    cam = cameras(vol)[0]
    cube, tri = RayCaster(sub, model="cubic-c1"), RayCaster(sub, model="trilinear")
    cube.set_isovalue(iso)
    tri.set_isovalue(iso)
    with pytest.raises(RayCastError, match="cells do not match"):
        tri.render(cam, SIZE, placement=grid.placement(brick, vol.origin))
    place = grid.placement(brick, vol.origin)
    assert cube.render(cam, SIZE, placement=place).hit.any()
    # cells beyond the samples read, samples beyond the volume
    for bad in (replace(place, cells=((8, 17), (0, 12), (0, 8))),
                replace(place, offset=(8, 0, 0))):
        with pytest.raises(RayCastError, match="not within its samples"):
            cube.render(cam, SIZE, placement=bad)


def test_the_numpy_path_clips_bricks_to_their_cells():
    """Without OpenCL a brick's own rays are clipped to its box by planes (close to the
    single cast, not bit for bit)."""
    f = np.linspace(-1.0, 1.0, 9)
    vol = Volume(np.add.outer(np.add.outer(f**2, f**2), f**2), spacing=(1.0, 1.0, 1.0))
    cam = Camera((4.3, -20.0, 6.1), (4.0, 4.0, 4.0))
    single = RayCaster(vol, model="trilinear", device="numpy")
    single.set_isovalue(0.5)
    want = single.render(cam, SIZE)
    got = _bricked(vol, "trilinear", 0.5, cam, (), 2, device="numpy")
    assert want.hit.sum() > 500
    assert np.mean(want.hit == got.hit) > 0.999
    both = want.hit & got.hit
    assert np.max(np.abs(want.depth[both] - got.depth[both])) < 1e-4
