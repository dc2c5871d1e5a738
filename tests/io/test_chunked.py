"""Chunked volumes read lazily (OME-Zarr multiscale, Zarr, HDF5): metadata without samples,
exact region reads, and renders equal to the in-memory volume's (issue 15)."""

import shutil
import warnings

import numpy as np
import pytest

import splineviz as sv
from splineviz.cli import main
from splineviz.core.chunked import ChunkedVolume
from splineviz.io.describe import describe
from splineviz.io.errors import InvalidDataError

#: OME-Zarr test volume: 128^3 uint8 in chunks of 32^3 (the 1024^3 / 128^3 one is -m slow)
N, CHUNK = 128, 32


def sphere_field(n: int) -> np.ndarray:
    """(n, n, n) uint8: a wavy ball, asymmetric so that a transposed read shows."""
    x = np.linspace(-1, 1, n)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    r = np.sqrt((X - 0.1) ** 2 + 1.3 * Y**2 + 0.8 * Z**2) + 0.08 * np.sin(7 * X + 3 * Z)
    return np.clip(255 * (1.2 - r), 0, 255).astype(np.uint8)


def write_ome_zarr(path, data, chunks, spacing=(1.0, 1.0, 1.0), levels=2):
    """``data`` (x, y, z) as an OME-Zarr image (z, y, x on disk, as the spec orders axes)
    with ``levels`` coarser levels."""
    import zarr
    from ome_zarr.io import parse_url

    with warnings.catch_warnings():
        # ome-zarr 0.18 warns about its own deprecated Scaler at import
        warnings.simplefilter("ignore", DeprecationWarning)
        from ome_zarr.writer import write_image
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image(data.transpose(2, 1, 0), root, axes="zyx",
                storage_options={"chunks": (chunks,) * 3},
                scale_factors=[{"z": 2**k, "y": 2**k, "x": 2**k} for k in range(1, levels + 1)],
                scale={"z": spacing[2], "y": spacing[1], "x": spacing[0]})
    return path


@pytest.fixture(scope="module")
def ome(tmp_path_factory):
    data = sphere_field(N)
    path = write_ome_zarr(tmp_path_factory.mktemp("ome") / "ball.ome.zarr", data, CHUNK,
                          spacing=(1.0, 1.5, 0.5))
    return path, data


def test_ome_zarr_opens_lazily_with_its_levels(ome):
    path, data = ome
    vol = sv.read_volume(path)
    assert isinstance(vol, ChunkedVolume)
    assert vol.shape == data.shape and vol.chunks == (CHUNK,) * 3 and vol.dtype == np.uint8
    assert vol.spacing == (1.0, 1.5, 0.5)
    assert [lv.shape for lv in vol.levels] == [(64, 64, 64), (32, 32, 32)]
    assert vol.levels[0].spacing == (2.0, 3.0, 1.0)
    box = ((5, 70), (33, 34), (100, 128))
    np.testing.assert_array_equal(vol.read(box).data, data[5:70, 33:34, 100:128])
    assert vol.read(box).origin == (5.0, 33 * 1.5, 50.0)
    lo, hi = vol.finite_range  # from the coarsest level, not the data
    assert 0 <= lo < hi <= 255
    # a file dialog picks the folder's metadata file: it opens the folder
    same = sv.read_volume(path / "zarr.json")
    assert isinstance(same, ChunkedVolume) and same.shape == vol.shape


def test_info_reads_no_samples(ome, tmp_path, capsys):
    path, _ = ome
    bare = tmp_path / "bare.ome.zarr"
    shutil.copytree(path, bare)
    # without any chunk of the full level, describing the volume still works
    shutil.rmtree(bare / "s0" / "c")
    info = describe(bare)
    assert info["format"] == "ome-zarr" and info["dims"] == [N, N, N]
    assert info["chunks"] == [CHUNK] * 3 and info["levels"] == "128x128x128 64x64x64 32x32x32"
    assert main(["info", str(bare)]) == 0
    assert "not read" in capsys.readouterr().out


def test_zarr_and_hdf5_arrays(tmp_path):
    import h5py
    import zarr

    data = sphere_field(24)[:, :20, :16]
    z = zarr.create_array(str(tmp_path / "a.zarr"), shape=data.shape, chunks=(8, 8, 8),
                          dtype="u1")
    z[:] = data
    z.attrs["spacing"] = [1, 2, 3]
    with h5py.File(tmp_path / "a.h5", "w") as f:
        d = f.create_dataset("scan/data", data=data, chunks=(8, 8, 8))
        d.attrs["element_size_um"] = [3.0, 2.0, 1.0]  # z, y, x as ImageJ writes it
        f.create_dataset("scan/mask", data=np.zeros((4, 4)))
    for name in ("a.zarr", "a.h5"):
        vol = sv.read_volume(tmp_path / name)
        assert isinstance(vol, ChunkedVolume) and vol.spacing == (1.0, 2.0, 3.0)
        np.testing.assert_array_equal(vol.read(((3, 9), (0, 20), (5, 6))).data,
                                      data[3:9, :, 5:6])
        np.testing.assert_array_equal(vol.data.compute(), data)
    with h5py.File(tmp_path / "two.h5", "w") as f:
        f.create_dataset("a", data=data)
        f.create_dataset("b", data=data)
    with pytest.raises(InvalidDataError, match="several 3-D datasets"):
        sv.read_volume(tmp_path / "two.h5")


def test_chunked_ome_zarr_renders_as_the_volume_in_memory(ome):
    from compute.bricked_helpers import assert_same_picture, compare_frames, local_client
    from compute.helpers import HAVE_CL

    from splineviz.compute.bricked import BrickedRayCaster
    from splineviz.core.camera import default_camera

    if not HAVE_CL:
        pytest.skip("no OpenCL device")
    path, data = ome
    vol = sv.read_volume(path)
    mem = sv.Volume(data, vol.spacing, vol.origin)
    cam = default_camera(vol.bounds)
    rc = sv.RayCaster(mem, model="cubic-c1")
    rc.set_isovalue(100)
    with local_client(2) as client:
        brc = BrickedRayCaster(vol, model="cubic-c1", client=client, brick_size=64)
        brc.set_isovalue(100)
        assert brc.stats["bricks"] == 8
        assert_same_picture(compare_frames(rc.render(cam, (80, 60)),
                                           brc.render(cam, (80, 60))))


def _read_png(path):
    from PIL import Image

    return np.asarray(Image.open(path))


def test_render_command_on_ome_zarr_matches_the_array(ome, tmp_path):
    from compute.helpers import HAVE_CL
    from distributed import LocalCluster

    if not HAVE_CL:
        pytest.skip("no OpenCL device")
    path, data = ome
    np.save(tmp_path / "ball.npy", data)
    common = ["--iso", "100", "--model", "trilinear", "--size", "64x48"]
    assert main(["render", str(tmp_path / "ball.npy"), *common, "-o",
                 str(tmp_path / "a.png")]) == 0
    # the OME-Zarr's spacing differs: give the array's (1, 1, 1) by rewriting it
    plain = write_ome_zarr(tmp_path / "plain.ome.zarr", data, CHUNK)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        assert main(["render", str(plain), *common, "--scheduler",
                     cluster.scheduler_address, "-o", str(tmp_path / "b.png")]) == 0
    np.testing.assert_array_equal(_read_png(tmp_path / "a.png"), _read_png(tmp_path / "b.png"))


def test_a_store_opened_through_its_metadata_file_is_named_after_its_folder(ome):
    from splineviz.model.opening import scene_from_path

    path, _ = ome
    meta = next(p for p in (path / n for n in ("zarr.json", ".zgroup")) if p.is_file())
    scene = scene_from_path(meta)
    assert [v.name for v in scene.volumes] == ["ball.ome.zarr"]
    assert scene_from_path(path).volumes[0].name == "ball.ome.zarr"
