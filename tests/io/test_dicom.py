"""DICOM: pydicom's own test files, written CT series, multi-frame files, series choice,
orientation and uneven spacing."""

from __future__ import annotations

import copy
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.io import load_volume_data
from splineviz.io.dicom import (
    SeriesChoiceError,
    _pixels,
    describe_series,
    list_series,
    series_file,
)
from splineviz.io.errors import FileFormatError, InvalidDataError

pydicom = pytest.importorskip("pydicom")
from pydicom.pixels import apply_rescale  # noqa: E402
from pydicom.uid import generate_uid  # noqa: E402

TEST_FILES = Path(pydicom.__file__).parent / "data" / "test_files"


def _expected_affine(ds, first_pos, dz):
    """Index (column, row, slice) -> patient (LPS) affine by DICOM PS3.3 C.7.6.2.1.1, from
    the tags themselves."""
    iop = np.array([float(v) for v in ds.ImageOrientationPatient])
    ps = [float(v) for v in ds.PixelSpacing]
    a = np.eye(4)
    a[:3, 0] = iop[:3] * ps[1]
    a[:3, 1] = iop[3:] * ps[0]
    a[:3, 2] = np.cross(iop[:3], iop[3:]) * dz
    a[:3, 3] = first_pos
    return a


def _reference(path: Path, vd):
    """What pydicom itself gives for the volume ``vd`` read from ``path``: values (column,
    row, slice) and affine."""
    ds = pydicom.dcmread(str(path))
    if int(ds.get("NumberOfFrames", 1) or 1) > 1:
        frames = ds.pixel_array.astype(np.float64) * float(ds.get("DoseGridScaling", 1.0))
        off = np.array([float(v) for v in ds.GridFrameOffsetVector])
        order = np.argsort(off)
        first = np.array([float(v) for v in ds.ImagePositionPatient])
        return (frames[order].transpose(2, 1, 0),
                _expected_affine(ds, first, off[order[1]] - off[order[0]]))
    uid = ds.SeriesInstanceUID
    members = []
    for f in sorted(path.parent.iterdir()):
        try:
            other = pydicom.dcmread(str(f))
        except Exception:  # noqa: BLE001 - not DICOM
            continue
        if other.get("SeriesInstanceUID") == uid and "PixelData" in other:
            members.append(other)
    normal = np.cross(*np.reshape([float(v) for v in ds.ImageOrientationPatient], (2, 3)))
    members.sort(key=lambda d: np.dot([float(v) for v in d.ImagePositionPatient], normal))
    stack = np.stack([apply_rescale(d.pixel_array, d) for d in members])
    pos = [np.array([float(v) for v in d.ImagePositionPatient]) for d in members]
    dz = float(np.dot(pos[1] - pos[0], normal))
    return stack.transpose(2, 1, 0), _expected_affine(ds, pos[0], dz)


def test_every_pydicom_test_file_is_read_as_pydicom_reads_it_or_refused_in_one_sentence():
    start = time.perf_counter()
    files = sorted(p for p in TEST_FILES.rglob("*") if p.is_file())
    assert len(files) > 150
    read, refused = [], {}
    for f in files:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SplinevizWarning)
                vd = load_volume_data(f)
        except SplinevizError as exc:
            text = str(exc)
            assert text and "\n" not in text and "Traceback" not in text, (f, text)
            refused[f.relative_to(TEST_FILES).as_posix()] = text
            continue
        data, affine = _reference(f, vd)
        np.testing.assert_allclose(np.asarray(vd.data, np.float64), data, rtol=1e-6,
                                   atol=1e-6 * max(1.0, float(np.abs(data).max())))
        np.testing.assert_allclose(vd.meta["affine"], affine, atol=1e-6)
        # axis-aligned here: the volume's geometry is the affine's diagonal and origin
        np.testing.assert_allclose(vd.spacing, np.diag(affine)[:3], atol=1e-9)
        np.testing.assert_allclose(vd.origin, affine[:3, 3], atol=1e-9)
        read.append(f.relative_to(TEST_FILES).as_posix())
    assert {"rtdose.dcm", "rtdose_expb.dcm", "rtdose_rle.dcm"} <= set(read)
    assert sum(r.startswith("dicomdirtests/98892001/CT5N/") for r in read) == 5
    # the reasons, not just any refusal
    assert "colour" in refused["SC_rgb_jpeg.dcm"]
    assert "Waveform" in refused["waveform_ecg.dcm"] and "without pixel data" in \
        refused["waveform_ecg.dcm"]
    assert "SR" in refused["test-SR.dcm"]
    assert "single 2-D DICOM image" in refused["CT_small.dcm"]
    assert "same position" in refused["MR_small.dcm"]
    assert time.perf_counter() - start < 60


def test_a_missing_pixel_decoder_is_named():
    path = TEST_FILES / "MR_small_jpeg_ls_lossless.dcm"
    try:
        _pixels(path)
    except FileFormatError as exc:
        assert "JPEG-LS" in str(exc) and "pylibjpeg" in str(exc) and "\n" not in str(exc)
    else:  # a JPEG-LS decoder is installed here: the pixels are pydicom's own
        pytest.skip("a JPEG-LS decoder is installed")


def test_rtdose_is_a_15_frame_dose_grid_with_its_spacing_and_unit(tmp_path):
    vd = load_volume_data(TEST_FILES / "rtdose.dcm")
    assert vd.data.shape == (10, 10, 15)
    assert vd.spacing == (10.0, 10.0, 5.0)
    assert vd.origin == pytest.approx((189.43125, 199.43125, -761.87))
    ds = pydicom.dcmread(str(TEST_FILES / "rtdose.dcm"))
    np.testing.assert_allclose(vd.data, ds.pixel_array.transpose(2, 1, 0) * 1e-6, rtol=1e-6)
    assert vd.meta["value_unit"] == "relative"  # the file's DoseUnits says RELATIVE
    ds.DoseUnits = "GY"
    ds.save_as(tmp_path / "gy.dcm")
    assert load_volume_data(tmp_path / "gy.dcm").meta["value_unit"] == "Gy"


def _write_ct_series(folder: Path, n=6, z0=-40.0, dz=2.5, uid=None, iop=(1, 0, 0, 0, 1, 0),
                     zs=None, number=3, description="abdomen"):
    """A CT series written with pydicom from its CT_small example: slice k holds
    ``100 * k + column`` stored, rescaled by slope 2 and intercept -1024; file names do not
    follow the slice order."""
    template = pydicom.dcmread(str(TEST_FILES / "CT_small.dcm"))
    folder.mkdir(exist_ok=True)
    uid = uid or generate_uid()
    iop = np.asarray(iop, dtype=float)
    normal = np.cross(iop[:3], iop[3:])
    zs = [z0 + k * dz for k in range(n)] if zs is None else zs
    values = []
    for k, z in enumerate(zs):
        ds = copy.deepcopy(template)
        ds.SeriesInstanceUID = uid
        ds.SeriesNumber = number
        ds.SeriesDescription = description
        ds.SOPInstanceUID = generate_uid()
        ds.ImageOrientationPatient = [f"{v:g}" for v in iop]
        ds.ImagePositionPatient = [f"{v:g}" for v in np.array([-10.0, 20.0, 0.0]) + z * normal]
        ds.RescaleSlope, ds.RescaleIntercept = 2, -1024
        px = (np.arange(ds.Columns)[None, :] + 100 * k + 3 * np.arange(ds.Rows)[:, None])
        ds.PixelData = px.astype(np.int16).tobytes()
        ds.save_as(folder / f"s{number}_img{(7 * k) % n:03d}_{k}.dcm")
        values.append(px * 2.0 - 1024)
    return uid, np.stack(values)  # (slice, row, column)


def test_one_file_of_a_written_ct_series_opens_the_whole_series(tmp_path):
    uid, values = _write_ct_series(tmp_path / "ct")
    (tmp_path / "ct" / "notes.txt").write_text("not DICOM")
    some = sorted((tmp_path / "ct").glob("*.dcm"))[2]
    vd = load_volume_data(some)
    assert vd.format == "dicom" and vd.meta["series"] == uid and vd.meta["value_unit"] == "HU"
    np.testing.assert_array_equal(vd.data, values.transpose(2, 1, 0))
    assert vd.spacing == pytest.approx((0.661468, 0.661468, 2.5))
    assert vd.origin == pytest.approx((-10.0, 20.0, -40.0))
    np.testing.assert_array_equal(load_volume_data(tmp_path / "ct").data, vd.data)
    v = sv.read_volume(some)  # the float32 volume of the whole series
    assert v.shape == (128, 128, 6)


def test_a_folder_of_two_series_asks_which(tmp_path):
    uid_a, a = _write_ct_series(tmp_path / "two", n=5, number=2, description="soft")
    uid_b, b = _write_ct_series(tmp_path / "two", n=4, number=7, description="bone",
                                dz=1.25)
    with pytest.raises(SeriesChoiceError) as info:
        sv.read_volume(tmp_path / "two")
    text = str(info.value)
    assert "2 DICOM series (0: CT #2 'soft', 5 image(s); 1: CT #7 'bone', 4 image(s))" in text
    assert "--series" in text
    found = list_series(tmp_path / "two")
    assert [s.uid for s in found] == [uid_a, uid_b] and [len(s.files) for s in found] == [5, 4]
    assert "'bone'" in found[1].label()
    assert load_volume_data(series_file(tmp_path / "two", 1)).data.shape[2] == 4
    assert load_volume_data(series_file(tmp_path / "two", uid_a)).data.shape[2] == 5
    with pytest.raises(InvalidDataError, match="no DICOM series '9'"):
        series_file(tmp_path / "two", 9)
    listed = describe_series(tmp_path / "two")
    assert len(listed["series"]) == 2 and listed["series"][0].startswith("0: CT #2")


def test_series_option_of_the_command_line(tmp_path, capsys):
    from splineviz.cli import main

    _write_ct_series(tmp_path / "two", n=5, number=2)
    uid_b, _ = _write_ct_series(tmp_path / "two", n=4, number=7)
    assert main(["info", str(tmp_path / "two")]) == 0
    out = capsys.readouterr().out
    assert "0: CT #2" in out and uid_b in out
    assert main(["info", str(tmp_path / "two"), "--series", uid_b]) == 0
    assert "128 128 4" in capsys.readouterr().out
    assert main(["info", str(tmp_path / "two"), "--series", "5"]) == 2


def test_a_missing_slice_is_resampled_with_a_warning(tmp_path):
    _, values = _write_ct_series(tmp_path / "gap", zs=[0, 2, 4, 8, 10])
    with pytest.warns(SplinevizWarning, match="resampled to 6 slices 2 mm apart"):
        vd = load_volume_data(tmp_path / "gap")
    assert vd.data.shape[2] == 6 and vd.spacing[2] == pytest.approx(2.0)
    np.testing.assert_allclose(vd.data[:, :, 2], values[2].T)  # z = 4
    np.testing.assert_allclose(vd.data[:, :, 3], values[2:4].mean(axis=0).T)  # z = 6
    np.testing.assert_allclose(vd.data[:, :, 4], values[3].T)  # z = 8
    _write_ct_series(tmp_path / "far", zs=[0, 1, 2, 60])
    with pytest.raises(InvalidDataError, match="unevenly"):
        load_volume_data(tmp_path / "far")


def test_orientation_flips_and_permutations_keep_world_positions(tmp_path):
    # rows run towards -y (anterior), slices along -z: both axes flipped, with a warning
    _write_ct_series(tmp_path / "flip", n=4, iop=(1, 0, 0, 0, -1, 0))
    with pytest.warns(SplinevizWarning, match="flipped"):
        vd = load_volume_data(tmp_path / "flip")
    assert min(vd.spacing) > 0
    a = np.asarray(vd.meta["affine"])
    assert a[1, 1] < 0 and a[2, 2] < 0
    ds = pydicom.dcmread(str(sorted((tmp_path / "flip").glob("*.dcm"))[0]))
    first = [float(v) for v in ds.ImagePositionPatient]  # any slice: its samples land right
    k = int(round((first[2] - a[2, 3]) / a[2, 2]))
    px = apply_rescale(ds.pixel_array, ds)
    for row, col in [(0, 0), (7, 5), (127, 127)]:
        world = a @ (col, row, k, 1)
        ijk = np.rint((world[:3] - np.array(vd.origin)) / np.array(vd.spacing)).astype(int)
        assert vd.data[tuple(ijk)] == px[row, col]
    # sagittal: columns along +y, rows along -z, the slice normal row x column along -x
    _write_ct_series(tmp_path / "sag", n=4, iop=(0, 1, 0, 0, 0, -1))
    with pytest.warns(SplinevizWarning, match="flipped"):
        vs = load_volume_data(tmp_path / "sag")
    assert vs.data.shape == (4, 128, 128)
    assert vs.spacing == pytest.approx((2.5, 0.661468, 0.661468))


def test_an_oblique_series_keeps_its_direction_or_is_refused_with_its_angle(tmp_path):
    t = np.radians(10)
    _write_ct_series(tmp_path / "obl", n=4, iop=(1, 0, 0, 0, np.cos(t), np.sin(t)))
    vd = load_volume_data(tmp_path / "obl")
    normal = np.cross([1, 0, 0], [0, np.cos(t), np.sin(t)])
    np.testing.assert_allclose(vd.direction, np.stack([[1, 0, 0], [0, np.cos(t), np.sin(t)],
                                                       normal], axis=1), atol=1e-6)
    with pytest.raises(InvalidDataError, match=r"oblique scan .*rotated by 10 degrees"):
        sv.read_volume(tmp_path / "obl", oblique="error")


def _enhanced(path: Path, order):
    """An enhanced CT multi-frame file: frames stored in ``order`` of their positions,
    rescale per frame, orientation and spacing shared."""
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.sequence import Sequence
    from pydicom.uid import ExplicitVRLittleEndian

    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2.1"  # Enhanced CT Image
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, \
        meta.MediaStorageSOPInstanceUID
    ds.Modality, ds.SeriesInstanceUID = "CT", generate_uid()
    ds.Rows, ds.Columns, ds.NumberOfFrames = 6, 5, len(order)
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
    shared = Dataset()
    pm, po = Dataset(), Dataset()
    pm.PixelSpacing, pm.SliceThickness = [0.5, 0.25], 3.0
    po.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    shared.PixelMeasuresSequence, shared.PlaneOrientationSequence = Sequence([pm]), \
        Sequence([po])
    ds.SharedFunctionalGroupsSequence = Sequence([shared])
    frames, per = [], []
    for k in order:
        item, pos, pvt = Dataset(), Dataset(), Dataset()
        pos.ImagePositionPatient = [1.0, 2.0, 3.0 * k]
        pvt.RescaleSlope, pvt.RescaleIntercept, pvt.RescaleType = 1 + k, -k, "HU"
        item.PlanePositionSequence, item.PixelValueTransformationSequence = \
            Sequence([pos]), Sequence([pvt])
        per.append(item)
        frames.append(np.full((6, 5), 10 + k, np.uint16) + np.arange(5, dtype=np.uint16))
    ds.PerFrameFunctionalGroupsSequence = Sequence(per)
    ds.PixelData = np.stack(frames).tobytes()
    ds.save_as(path, enforce_file_format=True)
    return np.stack([(np.full((6, 5), 10.0 + k) + np.arange(5)) * (1 + k) - k
                     for k in range(len(order))])


def test_enhanced_multi_frame_per_frame_positions_and_rescale(tmp_path):
    values = _enhanced(tmp_path / "enh.dcm", [2, 0, 3, 1])
    vd = load_volume_data(tmp_path / "enh.dcm")
    assert vd.data.shape == (5, 6, 4) and vd.spacing == (0.25, 0.5, 3.0)
    assert vd.origin == (1.0, 2.0, 0.0)
    np.testing.assert_allclose(vd.data, values.transpose(2, 1, 0))


def test_a_dicom_file_without_its_suffix_is_found_by_content(tmp_path):
    _write_ct_series(tmp_path / "ct", n=3)
    for f in (tmp_path / "ct").glob("*.dcm"):
        f.rename(f.with_suffix(""))
    any_file = sorted((tmp_path / "ct").iterdir())[0]
    assert load_volume_data(any_file).data.shape == (128, 128, 3)
