"""NIfTI and Analyze samples memory-mapped (issue 25, part 6): a volume too large to render in
one piece is read brick by brick from the mapped file, scaled and flipped as nibabel and the
eager path would; the pre-read size check counts the type a volume keeps."""

from __future__ import annotations

import pickle
import tracemalloc

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.chunked import ChunkedVolume
from splineviz.io import load_volume_data
from splineviz.io._util import check_volume_size, held_bytes
from splineviz.io.errors import CorruptFileError, DataTooLargeError
from splineviz.io.mapped import LAZY_SHARE_ENV, MappedArray, OrientedArray

nib = pytest.importorskip("nibabel")


def _samples(shape, dtype=np.int16):
    rng = np.random.default_rng(3)
    return rng.integers(0, 1000, shape).astype(dtype)


def _affine(flip_x=True):
    a = np.diag([-2.0 if flip_x else 2.0, 3.0, 1.5, 1.0])
    a[:3, 3] = (10.0, 20.0, 30.0)
    return a


def test_a_small_nifti_is_read_through_the_mapping(tmp_path):
    """Read whole, the samples come out of nibabel's memory map: nothing of the file's size
    is allocated before the volume's own copy."""
    data = _samples((128, 128, 64))  # 2 MiB of int16
    nib.Nifti1Image(data, np.eye(4)).to_filename(tmp_path / "v.nii")
    size = (tmp_path / "v.nii").stat().st_size
    load_volume_data(tmp_path / "v.nii")  # imports and first-use tables outside the trace
    tracemalloc.start()
    try:
        vd = load_volume_data(tmp_path / "v.nii")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert isinstance(vd.data, np.memmap) and vd.data.dtype == np.int16
    assert peak < size / 8, f"{peak} bytes traced for a {size}-byte file"
    np.testing.assert_array_equal(vd.data, np.asarray(nib.load(tmp_path / "v.nii").dataobj))


@pytest.mark.parametrize("scaled", [False, True])
@pytest.mark.parametrize("name", ["v.nii", "v.img"])
def test_a_large_nifti_opens_mapped_in_bricks_with_nibabels_values(tmp_path, monkeypatch,
                                                                   scaled, name):
    data = _samples((40, 30, 20))
    img = (nib.Nifti1Pair if name.endswith(".img") else nib.Nifti1Image)(data, _affine())
    if scaled:
        img.header.set_slope_inter(0.5, -3.0)
    img.to_filename(tmp_path / name)
    expected = np.asarray(nib.load(tmp_path / name).dataobj)  # nibabel's own values
    with pytest.warns(sv.SplinevizWarning, match="negative spacing along x"):
        whole = sv.read_volume(tmp_path / name)
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    with pytest.warns(sv.SplinevizWarning, match="negative spacing along x"):
        lazy = sv.read_volume(tmp_path / name)
    assert isinstance(lazy, ChunkedVolume) and lazy.shape == whole.shape == data.shape
    assert lazy.spacing == whole.spacing == (2.0, 3.0, 1.5)
    assert lazy.origin == whole.origin == (10.0 - 2.0 * 39, 20.0, 30.0)
    assert lazy.dtype == (np.float32 if scaled else np.int16) == whole.dtype
    assert isinstance(lazy.source, OrientedArray)
    inner = lazy.source.source if not scaled else lazy.source.source.source
    assert isinstance(inner, MappedArray)
    # x runs against the world: the volume holds the file's samples mirrored along i
    world = expected[::-1].astype(lazy.dtype)
    np.testing.assert_array_equal(whole.data, world)
    np.testing.assert_array_equal(np.asarray(lazy.data.compute()), world)
    box = ((3, 27), (4, 5), (0, 11))
    np.testing.assert_array_equal(lazy.read(box).data, world[3:27, 4:5, 0:11])
    again = pickle.loads(pickle.dumps(lazy.source))  # what a dask worker gets
    np.testing.assert_array_equal(again[0:5, 7:9, 2:3], world[0:5, 7:9, 2:3])


def test_axis_aligned_nifti_maps_without_reordering(tmp_path, monkeypatch):
    data = _samples((24, 20, 18), np.uint8)
    nib.Nifti1Image(data, _affine(flip_x=False)).to_filename(tmp_path / "v.nii")
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    lazy = sv.read_volume(tmp_path / "v.nii")
    assert isinstance(lazy.source, MappedArray) and lazy.dtype == np.uint8
    assert lazy.origin == (10.0, 20.0, 30.0)
    np.testing.assert_array_equal(np.asarray(lazy.data.compute()), data)


def test_gzipped_and_4d_nifti_are_read_whole(tmp_path, monkeypatch):
    data = _samples((12, 10, 8))
    nib.Nifti1Image(data, np.eye(4)).to_filename(tmp_path / "v.nii.gz")
    nib.Nifti1Image(np.stack([data, data + 1], axis=-1), np.eye(4)).to_filename(
        tmp_path / "t.nii")
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    np.testing.assert_array_equal(sv.read_volume(tmp_path / "v.nii.gz").data, data)
    with pytest.warns(sv.SplinevizWarning, match="2 frames"):
        np.testing.assert_array_equal(sv.read_volume(tmp_path / "t.nii").data, data)


def test_a_truncated_nifti_is_refused_before_mapping(tmp_path, monkeypatch):
    nib.Nifti1Image(_samples((20, 20, 20)), np.eye(4)).to_filename(tmp_path / "v.nii")
    raw = (tmp_path / "v.nii").read_bytes()
    (tmp_path / "v.nii").write_bytes(raw[: len(raw) // 2])
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    with pytest.raises(CorruptFileError, match="v.nii announces .* shorter"):
        sv.read_volume(tmp_path / "v.nii")


def test_the_size_check_counts_the_type_a_volume_keeps(monkeypatch):
    """A uint8 volume costs its stored samples and a uint8 volume, not a float32 copy."""
    shape = (1000, 1000, 1000)
    assert held_bytes(shape, np.uint8) == held_bytes(shape, 1) == 2 * 10**9
    assert held_bytes(shape, np.int16) == 4 * 10**9
    assert held_bytes(shape, np.float32) == 8 * 10**9
    assert held_bytes(shape, np.int32) == held_bytes(shape, 4) == 8 * 10**9
    assert held_bytes(shape, np.float64) == held_bytes(shape, 8) == 12 * 10**9
    assert held_bytes(shape, np.float16) == 6 * 10**9  # float16 is held as float32
    assert held_bytes(shape, np.dtype(">u2")) == 4 * 10**9  # byte order does not matter
    monkeypatch.setenv("SPLINEVIZ_MAX_VOLUME_BYTES", str(3 * 10**9))
    check_volume_size(shape, np.uint8, "u8.raw")  # 2 GB fits a 3 GB budget (5 GB did not)
    with pytest.raises(DataTooLargeError, match=r"f32.raw needs about 7.5 GiB"):
        check_volume_size(shape, np.float32, "f32.raw")


def test_a_uint8_file_within_budget_only_in_its_own_type_opens(tmp_path, monkeypatch):
    data = _samples((64, 64, 64), np.uint8)
    # gzipped: read whole, so the budget decides (a plain file this size would be mapped)
    nib.Nifti1Image(data, np.eye(4)).to_filename(tmp_path / "v.nii.gz")
    # room for the stored samples and a uint8 volume (2 bytes a sample), not for a float32
    # copy beside them (5) nor nibabel's float64 values (9)
    monkeypatch.setenv("SPLINEVIZ_MAX_VOLUME_BYTES", str(3 * 64**3))
    vol = sv.read_volume(tmp_path / "v.nii.gz")
    assert isinstance(vol, sv.Volume) and vol.dtype == np.uint8
    np.testing.assert_array_equal(vol.data, data)
    monkeypatch.setenv("SPLINEVIZ_MAX_VOLUME_BYTES", str(64**3))
    with pytest.raises(DataTooLargeError, match="v.nii.gz needs about"):
        sv.read_volume(tmp_path / "v.nii.gz")


def test_a_big_endian_mgh_with_permuted_axes_maps_in_native_order(tmp_path, monkeypatch):
    """MGH stores big-endian samples; its affine here swaps y and z and reverses x and z."""
    data = _samples((20, 18, 16))
    affine = np.array([[-1.0, 0, 0, 5], [0, 0, 2, 6], [0, -1.5, 0, 7], [0, 0, 0, 1]])
    nib.MGHImage(data, affine).to_filename(tmp_path / "v.mgh")
    with pytest.warns(sv.SplinevizWarning, match="negative spacing along x, z"):
        whole = sv.read_volume(tmp_path / "v.mgh")
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    with pytest.warns(sv.SplinevizWarning, match="negative spacing along x, z"):
        lazy = sv.read_volume(tmp_path / "v.mgh")
    assert lazy.dtype == np.dtype(np.int16) and lazy.dtype.isnative
    assert lazy.shape == whole.shape == (20, 16, 18)
    assert lazy.spacing == whole.spacing == (1.0, 2.0, 1.5)
    assert lazy.origin == whole.origin
    np.testing.assert_array_equal(np.asarray(lazy.data.compute()), whole.data)
    # world y is the file's k, world z its j reversed
    np.testing.assert_array_equal(whole.data, np.flip(data.transpose(0, 2, 1), (0, 2)))
