"""Oblique scans read brick by brick (issue 25): a chunked volume keeps its direction, its
bricks are cast in its own frame and the composite is turned into world once, so the bricked
picture is the in-memory one and its hits lie on the analytic world surface."""

from __future__ import annotations

import numpy as np
import pytest
from oblique_phantom import CENTRE, RADIUS, rotation

import splineviz as sv
from splineviz.compute.bricked import BrickedRayCaster
from splineviz.core.camera import Camera
from splineviz.core.chunked import ChunkedVolume
from splineviz.core.errors import SplinevizWarning
from splineviz.core.volume import VolumeError
from splineviz.io.errors import InvalidDataError
from splineviz.io.geometry import affine_from
from splineviz.io.mapped import LAZY_SHARE_ENV, OrientedArray

from .bricked_helpers import compare_frames, local_client

nib = pytest.importorskip("nibabel")

def sphere_nifti(path, rot, shape=(28, 26, 24), spacing=(1.0, 1.1, 0.9)):
    """An uncompressed NIfTI of ``|x - CENTRE|^2`` on a grid turned by ``rot`` and stored
    with its first axis reversed (as LAS files are)."""
    direction = rot.copy()
    direction[:, 0] *= -1
    half = 0.5 * (np.array(shape) - 1) * np.array(spacing)
    origin = CENTRE + np.array([0.7, -0.4, 0.3]) - direction @ half
    affine = affine_from(spacing, origin, direction)
    index = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), -1)
    world = nib.affines.apply_affine(affine, index)
    nib.save(nib.Nifti1Image(((world - CENTRE) ** 2).sum(-1).astype(np.float32), affine), path)


def world_camera():
    return Camera(CENTRE + np.array([30.0, -38.0, 22.0]), CENTRE, view_up=(0, 0, 1),
                  view_angle=30.0)


@pytest.fixture(scope="module")
def client():
    with local_client(workers=2, processes=False) as c:
        yield c


@pytest.fixture(scope="module")
def oblique(tmp_path_factory):
    """The same oblique NIfTI read whole (a Volume) and brick by brick (a ChunkedVolume of
    the mapped file)."""
    path = tmp_path_factory.mktemp("oblique") / "o.nii"
    sphere_nifti(path, rotation(18.0, -11.0, 33.0))
    # both paths undo the stored flip of x, and say so
    with pytest.warns(SplinevizWarning, match="negative spacing along x"):
        whole = sv.read_volume(path)
    mp = pytest.MonkeyPatch()
    try:
        mp.setenv(LAZY_SHARE_ENV, "0")
        with pytest.warns(SplinevizWarning, match="negative spacing along x"):
            lazy = sv.read_volume(path)
    finally:
        mp.undo()
    return whole, lazy


def test_a_large_oblique_nifti_opens_lazily_with_its_direction(oblique):
    whole, lazy = oblique
    assert isinstance(whole, sv.Volume) and isinstance(lazy, ChunkedVolume)
    assert not lazy.axis_aligned and isinstance(lazy.source, OrientedArray)
    np.testing.assert_allclose(lazy.direction, whole.direction, atol=1e-12)
    assert lazy.spacing == whole.spacing and lazy.origin == whole.origin
    np.testing.assert_array_equal(np.asarray(lazy.data.compute()), whole.data)
    np.testing.assert_allclose(lazy.world_bounds, whole.world_bounds)
    # a box read from the file is placed in the volume's own frame, as the volume's box is
    box = lazy.read(((3, 20), (5, 9), (0, 11)))
    assert box.axis_aligned
    np.testing.assert_array_equal(box.data, whole.data[3:20, 5:9, 0:11])
    np.testing.assert_allclose(box.origin, whole.index_to_world(np.array([[3, 5, 0]]))[0])
    # the coarse preview spans the same world box, turned the same way
    preview = lazy.preview_volume()
    np.testing.assert_allclose(preview.direction, whole.direction, atol=1e-12)
    np.testing.assert_allclose(preview.world_bounds, whole.world_bounds)


@pytest.mark.parametrize("model", ["trilinear", "cubic-c1"])
def test_oblique_bricks_are_the_in_memory_picture_on_the_world_sphere(oblique, client, model):
    whole, lazy = oblique
    cam, size = world_camera(), (64, 48)
    plane = (CENTRE + np.array([1.5, 0.0, 0.0]), (1.0, 0.2, 0.0))
    rc = sv.RayCaster(whole, model=model)
    rc.set_isovalue(RADIUS**2)
    single = rc.render(cam, size=size, clip_planes=[plane])
    # the chunked volume, and the in-memory one cut into bricks (its direction kept too)
    frames = []
    for source in (lazy, whole):
        brc = BrickedRayCaster(source, model=model, client=client, bricks=2)
        brc.set_isovalue(RADIUS**2)
        frames.append(brc.render(cam, size=size, clip_planes=[plane]))
        assert brc.stats["bricks_rendered"] > 1
        m = compare_frames(single, frames[-1])
        assert m["hits"] > 120 and m["hit_agreement"] >= 0.999, m
        assert m["depth_max"] <= 1e-5 and m["color_max"] <= 1, m
    bricked = frames[0]
    hit = bricked.hit
    np.testing.assert_allclose(bricked.position[hit & single.hit],
                               single.position[hit & single.hit], atol=1e-4)
    # world hits on the analytic sphere, on the kept side of the world clip plane
    radius = np.linalg.norm(bricked.position[hit] - CENTRE, axis=1)
    spread = 0.002 if model == "cubic-c1" else 0.06
    assert np.abs(radius - np.median(radius)).max() < spread
    assert abs(np.median(radius) - RADIUS) < 0.08
    n = np.asarray(plane[1]) / np.linalg.norm(plane[1])
    assert ((bricked.position[hit] - plane[0]) @ n).min() > -1e-3
    out = (bricked.position[hit] - CENTRE) / radius[:, None]
    assert np.min(np.sum(bricked.normal[hit] * out, axis=1)) > 0.99


def test_the_preview_of_an_oblique_chunked_volume_lands_in_world(oblique, client):
    """The coarse level keeps the direction: the preview stage and the GUI's preview caster
    put the surface on the world sphere (a missing or doubled rotation moves it by voxels)."""
    import dask.array as da

    from splineviz.core.chunked import Level

    whole, _ = oblique
    coarse = whole.data[::2, ::2, ::2]
    level = Level(da.from_array(coarse), tuple(2 * s for s in whole.spacing), whole.origin)
    vol = ChunkedVolume(da.from_array(whole.data, chunks=8), whole.spacing, whole.origin,
                        (level,), direction=whole.direction)
    brc = BrickedRayCaster(vol, model="trilinear", client=client, bricks=2)
    brc.set_isovalue(RADIUS**2)
    plane = (CENTRE, (0.0, 0.0, 1.0))  # keep the world's z above the centre
    stages = {stage: f for stage, _, _, f in brc.frames(world_camera(), size=(48, 36),
                                                        clip_planes=[plane])}
    gui = brc.preview_caster()  # what the window casts while the camera moves
    gui.set_isovalue(RADIUS**2)
    for frame in (stages["preview"], stages["exact"],
                  gui.render(world_camera(), (48, 36), clip_planes=[plane])):
        assert frame.hit.sum() > 50
        radius = np.linalg.norm(frame.position[frame.hit] - CENTRE, axis=1)
        assert abs(np.median(radius) - RADIUS) < 0.3
        assert frame.position[frame.hit][:, 2].min() >= CENTRE[2] - 1e-3


def test_a_chunked_direction_is_checked_as_a_volumes():
    import dask.array as da

    with pytest.raises(VolumeError, match="rotation"):
        ChunkedVolume(da.zeros((4, 4, 4)), direction=np.diag([1.0, 1.0, -1.0]))
    vol = ChunkedVolume(da.zeros((4, 4, 4)))
    assert vol.axis_aligned and vol.world_bounds == vol.bounds


def test_a_sheared_or_resampled_chunked_grid_is_refused_in_one_sentence():
    import dask.array as da

    from splineviz.io.chunked import to_chunked_volume
    from splineviz.io.volume_data import VolumeData

    sheared = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    sheared /= np.linalg.norm(sheared, axis=0)
    vd = VolumeData(da.zeros((8, 8, 8), chunks=4), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), "zarr",
                    {}, sheared)
    with pytest.raises(InvalidDataError, match="sheared grid .* cannot be resampled") as err:
        to_chunked_volume(vd, "big.zarr")
    assert "\n" not in str(err.value)
    vd.direction = rotation(0.0, 0.0, 20.0)
    with pytest.raises(InvalidDataError, match="oblique scan .* cannot be resampled"):
        to_chunked_volume(vd, "big.zarr", oblique="resample")
    with pytest.raises(InvalidDataError, match="oblique='error'"):
        to_chunked_volume(vd, "big.zarr", oblique="error")
    kept = to_chunked_volume(vd, "big.zarr")
    np.testing.assert_allclose(kept.direction, rotation(0.0, 0.0, 20.0), atol=1e-12)


def test_a_flipped_chunked_grid_is_turned_lazily_levels_included():
    """A signed-permutation direction is undone by transposing and flipping the dask array,
    the region reader and every level, as the eager path does."""
    import dask.array as da

    from splineviz.core.chunked import Level
    from splineviz.io.chunked import AxisSource, to_chunked_volume
    from splineviz.io.geometry import orientation
    from splineviz.io.volume_data import VolumeData

    stored = np.arange(6 * 5 * 4, dtype=np.float32).reshape(6, 5, 4)
    direction = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    spacing, origin = (1.0, 2.0, 3.0), (5.0, 6.0, 7.0)
    coarse = stored[::2, ::2, ::2]
    level = Level(da.from_array(coarse), (2.0, 4.0, 6.0), origin)
    vd = VolumeData(da.from_array(stored, chunks=3), spacing, origin, "zarr",
                    {"levels": (level,), "source": AxisSource(stored)}, direction)
    with pytest.warns(SplinevizWarning, match="negative spacing along x"):
        vol = to_chunked_volume(vd, "f.zarr")
    orient = orientation(vd.affine, stored.shape, "f.zarr")
    want = orient.apply(stored)
    assert vol.axis_aligned and vol.shape == want.shape
    assert vol.spacing == orient.spacing and vol.origin == orient.origin
    np.testing.assert_array_equal(np.asarray(vol.data.compute()), want)
    np.testing.assert_array_equal(vol.read(((1, 4), (0, 6), (2, 4))).data, want[1:4, :, 2:4])
    # every sample of the level keeps its world point
    lv = vol.levels[0]
    got = np.asarray(lv.data.compute())
    lo = orientation(affine_from(level.spacing, origin, direction), coarse.shape, "f.zarr")
    np.testing.assert_array_equal(got, lo.apply(coarse))
    assert lv.origin == lo.origin and lv.spacing == lo.spacing


def test_a_large_oblique_dicom_series_keeps_its_direction_lazily(tmp_path, monkeypatch):
    """A series tilted by 20 degrees about z, above the lazy share: read slice by slice with
    the rotation the series read whole keeps (it was refused before)."""
    import copy
    from pathlib import Path

    pydicom = pytest.importorskip("pydicom")
    from pydicom.uid import generate_uid

    template = pydicom.dcmread(str(Path(pydicom.__file__).parent / "data" / "test_files"
                                   / "CT_small.dcm"))
    c, s = np.cos(np.radians(20.0)), np.sin(np.radians(20.0))
    row, col = np.array([c, s, 0.0]), np.array([-s, c, 0.0])
    uid = generate_uid()
    folder = tmp_path / "ct"
    folder.mkdir()
    for k in range(5):
        ds = copy.deepcopy(template)
        ds.SeriesInstanceUID, ds.SOPInstanceUID = uid, generate_uid()
        ds.ImageOrientationPatient = [f"{v:.8f}" for v in (*row, *col)]
        ds.ImagePositionPatient = [f"{v:g}" for v in (5.0, 8.0, 2.0 * k)]
        ds.save_as(folder / f"img{k}.dcm")
    whole = sv.read_volume(folder)
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    lazy = sv.read_volume(folder)
    assert isinstance(whole, sv.Volume) and isinstance(lazy, ChunkedVolume)
    assert not whole.axis_aligned
    np.testing.assert_allclose(lazy.direction, whole.direction, atol=1e-12)
    assert lazy.spacing == whole.spacing and lazy.origin == whole.origin
    np.testing.assert_allclose(lazy.world_bounds, whole.world_bounds)
    np.testing.assert_array_equal(np.asarray(lazy.data.compute()), whole.data)
