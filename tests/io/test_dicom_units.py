"""RT dose units (issue 25, part 4): DoseGridScaling applies per file, DoseUnits names the
unit ("Gy", or "relative", never taken for Gy) in the volume's metadata and ``info``."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.cli import main
from splineviz.io import load_volume_data
from splineviz.io.describe import describe

pydicom = pytest.importorskip("pydicom")
from pydicom.uid import generate_uid  # noqa: E402

RTDOSE = Path(pydicom.__file__).parent / "data" / "test_files" / "rtdose.dcm"


def test_rtdose_values_and_unit_reach_info(tmp_path, capsys):
    ds = pydicom.dcmread(str(RTDOSE))
    stored = ds.pixel_array.transpose(2, 1, 0).astype(np.float64)
    vd = load_volume_data(RTDOSE)
    assert vd.meta["value_unit"] == "relative" and vd.meta["dose"] == "physical beam"
    np.testing.assert_allclose(vd.data, stored * float(ds.DoseGridScaling), rtol=1e-6)
    assert describe(RTDOSE)["values"] == "relative (RT dose, physical beam)"
    assert main(["info", str(RTDOSE)]) == 0
    out = capsys.readouterr().out
    assert "values: relative (RT dose, physical beam)" in out and "Gy" not in out

    ds.DoseUnits = "GY"
    ds.DoseGridScaling = "2.5e-5"
    ds.save_as(tmp_path / "gy.dcm")
    gy = load_volume_data(tmp_path / "gy.dcm")
    assert gy.meta["value_unit"] == "Gy"
    np.testing.assert_allclose(gy.data, stored * 2.5e-5, rtol=1e-6)
    assert describe(tmp_path / "gy.dcm")["values"].startswith("Gy ")

    del ds.DoseGridScaling  # optional in the RT Dose module: the values are the stored ones
    ds.save_as(tmp_path / "unscaled.dcm")
    plain = load_volume_data(tmp_path / "unscaled.dcm")
    assert plain.meta["value_unit"] == "Gy"
    np.testing.assert_array_equal(plain.data, stored.astype(np.float32))


def _dose_planes(folder: Path, scales, units):
    """rtdose.dcm's first frames written as single-frame dose files, each with its own
    DoseGridScaling and DoseUnits."""
    ds = pydicom.dcmread(str(RTDOSE))
    px = ds.pixel_array
    offsets = [float(v) for v in ds.GridFrameOffsetVector]
    ipp = np.array([float(v) for v in ds.ImagePositionPatient])
    uid = generate_uid()
    folder.mkdir()
    for k, (scale, unit) in enumerate(zip(scales, units, strict=True)):
        one = copy.deepcopy(ds)
        one.NumberOfFrames = 1
        del one.GridFrameOffsetVector
        del one.FrameIncrementPointer
        one.PixelData = np.ascontiguousarray(px[k]).tobytes()
        one.ImagePositionPatient = [f"{v:.4f}" for v in ipp + [0, 0, offsets[k] - offsets[0]]]
        one.SOPInstanceUID = generate_uid()
        one.SeriesInstanceUID = uid
        one.DoseGridScaling = f"{scale:g}"
        one.DoseUnits = unit
        one.save_as(folder / f"plane{k}.dcm")
    return px


def test_each_file_of_a_dose_series_has_its_own_scaling(tmp_path):
    scales = [1e-4, 2e-4, 5e-5, 1e-4]
    px = _dose_planes(tmp_path / "planes", scales, ["GY"] * 4)
    vd = load_volume_data(tmp_path / "planes")
    assert vd.meta["value_unit"] == "Gy" and vd.data.shape == (10, 10, 4)
    expected = np.stack([px[k] * s for k, s in enumerate(scales)]).transpose(2, 1, 0)
    np.testing.assert_allclose(vd.data, expected, rtol=1e-6)
    assert sv.read_volume(tmp_path / "planes").shape == (10, 10, 4)


def test_a_dose_series_mixing_units_is_refused(tmp_path):
    _dose_planes(tmp_path / "mixed", [1e-4] * 3, ["GY", "RELATIVE", "GY"])
    with pytest.raises(sv.SplinevizError, match=r"different units \(Gy, relative\)") as e:
        sv.read_volume(tmp_path / "mixed")
    assert "\n" not in str(e.value)
