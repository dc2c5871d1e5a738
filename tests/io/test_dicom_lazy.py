"""A DICOM series above the lazy share is read slice by slice through the chunked path
(issue 25, part 5): same values and geometry as read whole, flips included."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.chunked import ChunkedVolume
from splineviz.io import load_volume_data
from splineviz.io.dicom import SeriesSlices
from splineviz.io.mapped import LAZY_SHARE_ENV

pydicom = pytest.importorskip("pydicom")
from pydicom.uid import generate_uid  # noqa: E402

CT_SMALL = Path(pydicom.__file__).parent / "data" / "test_files" / "CT_small.dcm"


def _series(folder: Path, n=7, iop=(1, 0, 0, 0, -1, 0)):
    """CT_small as ``n`` slices 2 mm apart, rows running against y (a flip): slice k holds
    ``40 * k + column + 3 * row`` stored, rescaled by slope 2 and intercept -1024."""
    template = pydicom.dcmread(str(CT_SMALL))
    folder.mkdir()
    uid = generate_uid()
    iop = np.asarray(iop, dtype=float)
    normal = np.cross(iop[:3], iop[3:])
    values = []
    for k in range(n):
        ds = copy.deepcopy(template)
        ds.SeriesInstanceUID, ds.SOPInstanceUID = uid, generate_uid()
        ds.ImageOrientationPatient = [f"{v:g}" for v in iop]
        ds.ImagePositionPatient = [f"{v:g}" for v in np.array([5.0, 8.0, 0.0]) + 2 * k * normal]
        ds.RescaleSlope, ds.RescaleIntercept = 2, -1024
        px = np.arange(ds.Columns)[None, :] + 40 * k + 3 * np.arange(ds.Rows)[:, None]
        ds.PixelData = px.astype(np.int16).tobytes()
        ds.save_as(folder / f"img{(3 * k) % n}_{k}.dcm")
        values.append(px * 2.0 - 1024)
    return np.stack(values)


def test_a_series_above_the_lazy_share_is_read_slice_by_slice(tmp_path, monkeypatch):
    _series(tmp_path / "ct")
    with pytest.warns(sv.SplinevizWarning, match="negative spacing along y, z"):
        whole = sv.read_volume(tmp_path / "ct")
    assert isinstance(whole, sv.Volume)
    monkeypatch.setenv(LAZY_SHARE_ENV, "0")
    with pytest.warns(sv.SplinevizWarning, match="negative spacing along y, z"):
        lazy = sv.read_volume(tmp_path / "ct")
    assert isinstance(lazy, ChunkedVolume) and lazy.shape == whole.shape == (128, 128, 7)
    assert lazy.spacing == whole.spacing and lazy.origin == whole.origin
    np.testing.assert_array_equal(np.asarray(lazy.data.compute()), whole.data)
    box = ((10, 70), (100, 128), (2, 6))
    np.testing.assert_array_equal(lazy.read(box).data, whole.data[10:70, 100:128, 2:6])
    with pytest.warns(sv.SplinevizWarning, match="negative spacing"):
        vd = load_volume_data(tmp_path / "ct")
    assert vd.meta["value_unit"] == "HU" and vd.data.chunks[2] == (7,)  # whole slices


def test_the_slice_reader_reads_only_its_files_and_pickles(tmp_path):
    values = _series(tmp_path / "ct", n=4, iop=(1, 0, 0, 0, 1, 0))
    files = sorted((tmp_path / "ct").iterdir(), key=lambda f: int(f.stem.split("_")[1]))
    reader = pickle.loads(pickle.dumps(SeriesSlices(files, 128, 128)))
    np.testing.assert_array_equal(reader[1:3, 5:9, 0:128], values[1:3, 5:9].astype(np.float32))
    files[0].write_bytes(b"damaged")  # a region that does not meet slice 0 never reads it
    np.testing.assert_array_equal(reader[2:4, 0:2, 0:3], values[2:4, 0:2, 0:3])
    with pytest.raises(sv.SplinevizError, match="img0_0.dcm"):
        reader[0:1, 0:2, 0:2]
