"""Volumes keep their file's sample type from the reader to the device (issue 25, part 6):
8- and 16-bit integers and float32 as they are, memory-mapped where the file allows, with no
float32 copy of the whole volume on the way to a frame."""

from __future__ import annotations

import mmap
import tracemalloc

import numpy as np
import pytest
from compute.helpers import HAVE_CL

import splineviz as sv
from splineviz.core.chunked import ChunkedVolume
from splineviz.io import mapped


def _mapped(array: np.ndarray) -> bool:
    """Whether ``array``'s memory is a mapping of a file."""
    base = array
    while isinstance(base, np.ndarray):
        base = base.base
    return isinstance(base, mmap.mmap)


def _blob(n: int, dtype) -> np.ndarray:
    """An (n, n, n) ball with a noisy rim in ``dtype`` (values 0..200)."""
    x = np.linspace(-1, 1, n)
    r = np.sqrt(x[:, None, None] ** 2 + x[None, :, None] ** 2 + x[None, None, :] ** 2)
    noise = np.random.default_rng(0).integers(0, 20, (n, n, n))
    return np.clip(180 * (1.2 - r / 0.7), 0, 180).astype(dtype) + noise.astype(dtype)


@pytest.mark.parametrize("dtype", [np.uint8, np.int8, np.uint16, np.int16, np.float32])
def test_volume_keeps_the_types_float32_holds_exactly(dtype):
    data = _blob(6, dtype)
    vol = sv.Volume(data)
    assert vol.dtype == dtype and vol.data.dtype == dtype
    assert np.shares_memory(vol.data, data)  # no copy of a C-ordered array of a kept type
    values = vol.values()
    assert values.dtype == np.float32
    np.testing.assert_array_equal(values, data.astype(np.float32))
    np.testing.assert_array_equal(vol.values((slice(1, 3), 2)),
                                  data[1:3, 2].astype(np.float32))
    assert vol.finite_range == (float(data.min()), float(data.max()))
    assert vol.nonfinite_count == 0


def test_other_types_become_float32_and_bool_uint8():
    assert sv.Volume(np.arange(24).reshape(2, 3, 4)).dtype == np.float32  # int64
    assert sv.Volume(np.zeros((2, 2, 2))).dtype == np.float32  # float64
    flags = np.zeros((2, 2, 3), bool)
    flags[1, 1, 2] = True
    assert sv.Volume(flags).dtype == np.uint8 and sv.Volume(flags).finite_range == (0.0, 1.0)
    big_endian = np.arange(8, dtype=">i2").reshape(2, 2, 2)
    vol = sv.Volume(big_endian)
    assert vol.dtype == np.dtype("int16") and vol.dtype.isnative
    np.testing.assert_array_equal(vol.data, np.arange(8).reshape(2, 2, 2))


def test_float_ranges_skip_nonfinite_samples_slab_by_slab(monkeypatch):
    from splineviz.core import volume as volume_module

    monkeypatch.setattr(volume_module, "SLAB_SAMPLES", 4)  # several slabs, one all NaN
    data = np.arange(27, dtype=np.float32).reshape(3, 3, 3)
    data[0] = np.nan
    data[2, 2, 2] = np.inf
    vol = sv.Volume(data)
    assert vol.finite_range == (9.0, 25.0) and vol.nonfinite_count == 10


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint16])
def test_npy_and_raw_files_keep_their_type(tmp_path, dtype):
    data = _blob(9, dtype)
    np.save(tmp_path / "v.npy", data)
    vol = sv.read_volume(tmp_path / "v.npy")
    assert vol.dtype == dtype
    np.testing.assert_array_equal(vol.data, data)
    assert _mapped(vol.data)  # not read into a copy
    # raw, big-endian, x fastest
    (tmp_path / "v.raw").write_bytes(data.astype(np.dtype(dtype).newbyteorder(">"))
                                     .tobytes(order="F"))
    raw = sv.read_volume(tmp_path / "v.raw", dims=data.shape, dtype=np.dtype(dtype).name,
                         byteorder="big")
    assert raw.dtype == dtype and raw.dtype.isnative
    np.testing.assert_array_equal(raw.data, data)


def test_nonfinite_refusal_and_fill_without_a_whole_copy(tmp_path):
    data = _blob(8, np.float32)
    data[3, 4, 5] = np.nan
    np.save(tmp_path / "nan.npy", data)
    with pytest.raises(sv.SplinevizError, match="1 NaN or infinite samples"):
        sv.read_volume(tmp_path / "nan.npy")
    with pytest.warns(sv.SplinevizWarning, match="replaced by 0"):
        vol = sv.read_volume(tmp_path / "nan.npy", nonfinite="fill")
    assert vol.dtype == np.float32 and vol.data[3, 4, 5] == 0.0
    np.save(tmp_path / "allnan.npy", np.full((4, 4, 4), np.nan, np.float32))
    with pytest.raises(sv.SplinevizError, match="no finite samples"):
        sv.read_volume(tmp_path / "allnan.npy")
    assert np.isnan(np.load(tmp_path / "nan.npy")[3, 4, 5])  # the file is untouched


def test_a_volume_too_large_for_one_piece_opens_mapped_in_bricks(tmp_path, monkeypatch):
    data = _blob(40, np.uint8)
    np.save(tmp_path / "big.npy", data)
    (tmp_path / "big.raw").write_bytes(data.tobytes(order="F"))
    monkeypatch.setenv("SPLINEVIZ_LAZY_SHARE", "0")
    vol = sv.read_volume(tmp_path / "big.npy")
    assert isinstance(vol, ChunkedVolume) and vol.dtype == np.uint8
    assert isinstance(vol.source, mapped.MappedArray)
    part = vol.read(((3, 20), (0, 40), (7, 9)))
    assert part.dtype == np.uint8
    np.testing.assert_array_equal(part.data, data[3:20, :, 7:9])
    raw = sv.read_volume(tmp_path / "big.raw", dims=data.shape, dtype="uint8")
    assert isinstance(raw, ChunkedVolume)
    np.testing.assert_array_equal(raw.read(((0, 40), (5, 6), (0, 40))).data, data[:, 5:6])
    import pickle

    again = pickle.loads(pickle.dumps(vol.source))  # what a worker process gets: the path
    np.testing.assert_array_equal(again[1:4, 2, 3:5], data[1:4, 2, 3:5])


@pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")
@pytest.mark.parametrize("model", ["trilinear", "cubic-c1"])
def test_no_float_copy_of_the_volume_on_the_way_to_a_frame(tmp_path, model):
    def frame_of(path, n):
        vol = sv.read_volume(path)
        rc = sv.RayCaster(vol, model=model)
        rc.set_isovalue(0.5 * sum(vol.finite_range))
        eye, centre = (n / 2, -1.5 * n, n / 2), (n / 2, n / 2, n / 2)
        return vol, rc.render(sv.Camera(eye, centre), size=(48, 36))

    np.save(tmp_path / "small.npy", _blob(16, np.uint8))
    frame_of(tmp_path / "small.npy", 16)  # imports, kernels built and their tables: once
    n = 128
    np.save(tmp_path / "ball.npy", _blob(n, np.uint8))
    tracemalloc.start()
    try:
        vol, frame = frame_of(tmp_path / "ball.npy", n)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert vol.dtype == np.uint8 and frame.hit.sum() > 100
    # a float32 copy of the samples would be 4 bytes per sample, even a uint8 copy 1 (the
    # device buffers are the OpenCL driver's, not traced)
    assert peak < 1.0 * n**3, f"{peak / n**3:.2f} bytes traced per sample"


def test_large_raw_nrrd_and_mrc_read_mapped_in_bricks(tmp_path, monkeypatch):
    import mrcfile
    import nrrd

    data = _blob(24, np.int16)
    data = data[:, :20, :18].copy()
    nrrd.write(str(tmp_path / "v.nrrd"), data, {"encoding": "raw", "endian": "big",
                                                 "spacings": [1.0, 2.0, 3.0]}, index_order="F")
    nrrd.write(str(tmp_path / "d.nhdr"), data, {"encoding": "raw"}, index_order="F",
               detached_header=True)
    with mrcfile.new(str(tmp_path / "v.mrc")) as m:
        m.set_data(np.ascontiguousarray(data.transpose(1, 2, 0)))  # sections along y
        m.header.mapc, m.header.mapr, m.header.maps = 1, 3, 2  # columns x, rows z
    eager = {name: sv.read_volume(tmp_path / name) for name in ("v.nrrd", "d.nhdr", "v.mrc")}
    monkeypatch.setenv("SPLINEVIZ_LAZY_SHARE", "0")
    for name, whole in eager.items():
        assert whole.dtype == np.int16, name
        np.testing.assert_array_equal(whole.data, data, err_msg=name)
        lazy = sv.read_volume(tmp_path / name)
        assert isinstance(lazy, ChunkedVolume) and lazy.shape == data.shape, name
        assert lazy.spacing == whole.spacing and lazy.origin == whole.origin, name
        box = ((2, 19), (3, 4), (0, 18))
        np.testing.assert_array_equal(lazy.read(box).data, data[2:19, 3:4], err_msg=name)
    assert eager["v.nrrd"].spacing == (1.0, 2.0, 3.0)
