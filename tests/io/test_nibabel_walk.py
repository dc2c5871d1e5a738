"""Every file of nibabel's own test data: read with the same values and affine as nibabel
itself gives, or refused in one sentence that says why; never a traceback."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.io import describe, load_volume_data, read_volume, read_volume_sequence
from splineviz.io.errors import DataFileNotFoundError, InvalidDataError
from splineviz.io.geometry import orientation

nib = pytest.importorskip("nibabel")
DATA = Path(nib.__file__).parent / "tests" / "data"
FILES = sorted(p.name for p in DATA.iterdir() if p.is_file()) if DATA.is_dir() else []

#: the files the issue names among those that must be read (values and affine)
MUST_READ = {"small.mnc", "minc2_1_scale.mnc", "minc2-no-att.mnc", "minc2_baddim.mnc",
             "minc1-no-att.mnc", "minc1_1_scale.mnc", "minc1_4d.mnc", "tiny.mnc",
             "test.mgz", "phantom_EPI_asc_CLEAR_2_1.PAR", "phantom_varscale.PAR",
             "example4d+orig.HEAD", "scaled+tlrc.HEAD"}


def nibabel_reading(path: Path):
    """nibabel's own image, or None where nibabel itself reads no volume from the file."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            img = nib.load(str(path))
            if not isinstance(img, nib.spatialimages.SpatialImage) or len(img.shape) < 3:
                return None
            np.asanyarray(img.dataobj[(0,) * len(img.shape)])  # the payload is there
            return img
    except Exception:  # noqa: BLE001 - whatever nibabel refuses, the file is not its volume
        return None


def one_sentence(exc: BaseException) -> bool:
    text = str(exc)
    return isinstance(exc, SplinevizError) and 10 < len(text) <= 300 and "\n" not in text \
        and "Traceback" not in text


def frame_of(img, spatial, index):
    """nibabel's samples of one frame, spatial axes in the affine's i, j, k order."""
    full = np.asanyarray(img.dataobj)
    extra = [a for a in range(full.ndim) if a not in spatial]
    key = [slice(None)] * full.ndim
    for a, i in zip([a for a in extra if full.shape[a] > 1], index, strict=False):
        key[a] = i
    for a in extra:
        if isinstance(key[a], slice):
            key[a] = 0
    block = full[tuple(key)]
    kept = [a for a in range(full.ndim) if isinstance(key[a], slice)]
    return np.transpose(block, [kept.index(a) for a in spatial])


@pytest.mark.skipif(not FILES, reason="nibabel ships no test data here")
def test_every_nibabel_test_file_reads_like_nibabel_or_is_refused_in_one_sentence():
    read, refused = set(), {}
    for name in FILES:
        img = nibabel_reading(DATA / name)
        try:
            check_one(name, img, read, refused)
        finally:
            # nibabel's PAR/REC images keep their REC file open until closed
            handle = getattr(getattr(img, "dataobj", None), "file_like", None)
            if hasattr(handle, "close"):
                handle.close()
    assert MUST_READ <= read, sorted(MUST_READ - read)
    # rotated scans keep their rotation as the volume's direction; test.mgz's affine is
    # sheared (its axes are not perpendicular), so no rotation places it: resampled
    oblique = {"phantom_varscale.PAR", "phantom_EPI_asc_CLEAR_2_1.PAR", "example4d.nii.gz",
               "example_nifti2.nii.gz"}
    assert {n + " (oblique)" for n in oblique} <= read
    assert "test.mgz (resampled)" in read
    # shipped without its .img: nibabel parses the header, but there are no samples to read
    for pair in ("analyze.hdr", "nifti1.hdr", "nifti2.hdr"):
        if pair in refused:
            assert isinstance(refused[pair], DataFileNotFoundError), pair
            assert pair.replace(".hdr", ".img") in str(refused[pair])


def check_one(name, img, read, refused):
    """One file: read like nibabel (``read``) or refused in one sentence (``refused``)."""
    path = DATA / name
    try:
        vd = load_volume_data(path)
    except SplinevizError as exc:
        assert one_sentence(exc), (name, str(exc))
        assert img is None, f"{name}: nibabel reads it but splineviz refused: {exc}"
        refused[name] = exc
        return
    if img is None and vd.format.startswith("dicom"):
        # nibabel's two DICOM slices (0.3 degrees oblique) are a series pydicom reads: each
        # file's pixels are one slice of the volume (values with their rescale)
        import pydicom

        ds = pydicom.dcmread(path)
        px = ds.pixel_array * float(ds.get("RescaleSlope", 1)) + float(
            ds.get("RescaleIntercept", 0))
        data = np.asarray(vd.data)
        assert any(np.array_equal(np.sort(data[..., k].ravel()), np.sort(px.ravel()))
                   for k in range(data.shape[2])), name
        read.add(name + " (DICOM)")
        return
    assert img is not None, f"{name}: read although nibabel reads no volume from it"
    read.add(name)
    np.testing.assert_allclose(vd.affine, img.affine, rtol=1e-6, atol=1e-6,
                               err_msg=name)
    np.testing.assert_allclose(describe(path)["affine"], img.affine, rtol=1e-6, atol=1e-6,
                               err_msg=name)  # what `splineviz info` prints
    spatial = vd.meta.get("spatial_axes", (0, 1, 2))
    want = frame_of(img, spatial, ())
    assert vd.data.shape == want.shape, name
    np.testing.assert_array_equal(vd.data, want, err_msg=name)
    if vd.frames is not None:  # the last frame too, read on its own
        last = tuple(a.size - 1 for a in vd.frames.axes)
        np.testing.assert_array_equal(vd.frames.read(last), frame_of(img, spatial, last),
                                      err_msg=name)
    # the Volume: the same samples at the same world points (an oblique grid through its
    # direction), or resampled (a sheared grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SplinevizWarning)
        vol = read_volume(path, nonfinite="fill")
    orient = orientation(img.affine, vd.data.shape, name)
    if orient.oblique and orient.sheared:
        # tests/io/test_geometry.py checks the resampled values
        assert vol.axis_aligned and np.all(np.isfinite(vol.values())), name
        assert min(vol.shape) >= 2, name
        read.add(name + " (resampled)")
        return
    if orient.oblique:
        assert not vol.axis_aligned, name
        read.add(name + " (oblique)")
    else:
        assert vol.axis_aligned, name
    np.testing.assert_allclose(vol.origin, orient.origin, atol=1e-5, err_msg=name)
    finite = np.isfinite(want)
    np.testing.assert_allclose(orient.apply(np.where(finite, want, 0))[
        orient.apply(finite)], vol.data[orient.apply(finite)], rtol=1e-6, err_msg=name)
    # a few file indices: our index of the same sample (transpose and flips undone) lies at
    # nibabel's img.affine @ (i, j, k, 1) and holds nibabel's value
    shape = np.array(want.shape)
    rng = np.random.default_rng(0)
    file_index = np.vstack([np.zeros(3, int), shape - 1, rng.integers(0, shape, (8, 3))])
    ours = np.empty_like(file_index)
    for w, ax in enumerate(orient.perm):
        ours[:, w] = shape[ax] - 1 - file_index[:, ax] if orient.flips[w] else \
            file_index[:, ax]
    world = vol.to_world(vol.index_to_world(ours.astype(float)))
    scale = max(1.0, float(np.abs(img.affine).max()))
    np.testing.assert_allclose(world, nib.affines.apply_affine(img.affine, file_index),
                               atol=1e-5 * scale, err_msg=name)
    got = vol.data[tuple(ours.T)]
    expect = want[tuple(file_index.T)]
    ok = np.isfinite(expect)
    np.testing.assert_allclose(got[ok], expect[ok], rtol=1e-6, err_msg=name)


@pytest.mark.skipif(not (DATA / "small.mnc").exists(), reason="nibabel ships no MINC2 file")
def test_minc2_is_read_with_its_scaling_and_geometry_not_as_bare_hdf5(tmp_path):
    """The issue's small.mnc: nibabel gives 0.12..92.9 and voxel sizes 9, 8, 7 mm; read as a
    bare HDF5 dataset it was -32768..32767 at spacing 1. Renamed .h5 it is still MINC2."""
    img = nib.load(str(DATA / "small.mnc"))
    want = np.asanyarray(img.dataobj)
    for path in (DATA / "small.mnc", tmp_path / "small.h5"):
        if not path.exists():
            path.write_bytes((DATA / "small.mnc").read_bytes())
        vd = load_volume_data(path)
        assert vd.format == "minc"
        np.testing.assert_array_equal(vd.data, want)
        assert float(vd.data.min()) == pytest.approx(0.1185, abs=1e-3)
        assert float(vd.data.max()) == pytest.approx(92.877, abs=1e-3)
        vol = read_volume(path)
        assert sorted(vol.spacing) == [7.0, 8.0, 9.0]
        assert vol.spacing == (7.0, 8.0, 9.0)  # file order z, y, x: world x is 7 mm


@pytest.mark.skipif(not (DATA / "functional.nii").exists(), reason="no 4-D NIfTI")
def test_4d_nifti_is_a_sequence_of_volumes_with_its_times():
    img = nib.load(str(DATA / "functional.nii"))
    seq = read_volume_sequence(DATA / "functional.nii")
    assert len(seq) == 20 and seq.axis.name == "time" and seq.axis.unit == "s"
    assert seq.times[:3] == pytest.approx((0.0, 2.0, 4.0))
    with pytest.warns(SplinevizWarning, match="negative spacing"):
        frame7 = seq[7]
    want = np.asanyarray(img.dataobj)[..., 7][::-1]  # stored LAS: x reversed
    np.testing.assert_allclose(frame7.data, want, rtol=1e-6)
    with pytest.warns(SplinevizWarning) as notes:
        first = read_volume(DATA / "functional.nii")
    assert any("20 frames along its time axis" in str(n.message) for n in notes)
    np.testing.assert_allclose(first.data, np.asanyarray(img.dataobj)[..., 0][::-1], rtol=1e-6)


@pytest.mark.skipif(not (DATA / "minc1_4d.mnc").exists(), reason="no 4-D MINC")
def test_4d_minc_names_its_time_axis_from_the_file():
    seq = read_volume_sequence(DATA / "minc1_4d.mnc")
    assert (len(seq), seq.axis.name) == (2, "time")
    assert seq.times == (0.0, 1.0)  # the time dimension's start and step
    img = nib.load(str(DATA / "minc1_4d.mnc"))
    np.testing.assert_allclose(seq[1].data, np.asanyarray(img.dataobj)[1].transpose(2, 1, 0),
                               rtol=1e-6)


def test_channel_axis_is_chosen(tmp_path):
    """A 5-D NIfTI (x, y, z, t, vector components): the sequence runs along time at the
    chosen channel; a 4-D file's only extra axis can be taken as the channel."""
    rng = np.random.default_rng(3)
    data = rng.random((4, 5, 6, 3, 2)).astype(np.float32)
    img = nib.Nifti1Image(data, np.eye(4))
    img.header.set_xyzt_units("mm", "sec")
    nib.save(img, tmp_path / "vec.nii")
    seq = read_volume_sequence(tmp_path / "vec.nii", channel=1)
    assert (len(seq), seq.axis.name, seq.channel, seq.channels) == (3, "time", 1, 2)
    np.testing.assert_array_equal(seq[2].data, data[..., 2, 1])
    with pytest.warns(SplinevizWarning, match="2 channels"):
        read_volume(tmp_path / "vec.nii")
    with pytest.warns(SplinevizWarning, match="3 frames along its time axis"):
        chosen = read_volume(tmp_path / "vec.nii", channel=1)
    np.testing.assert_array_equal(chosen.data, data[..., 0, 1])
    with pytest.raises(InvalidDataError, match="channel 5 is not one"):
        read_volume_sequence(tmp_path / "vec.nii", channel=5)
    nib.save(nib.Nifti1Image(data[..., 0, :], np.eye(4)), tmp_path / "two.nii")
    only = read_volume_sequence(tmp_path / "two.nii", channel=1)
    assert len(only) == 1 and only.channel == 1
    np.testing.assert_array_equal(only[0].data, data[..., 0, 1])
    nib.save(nib.Nifti1Image(data[..., 0, 0], np.eye(4)), tmp_path / "three.nii")
    with pytest.raises(InvalidDataError, match="no channel axis"):
        read_volume(tmp_path / "three.nii", channel=0)


def test_the_gui_read_path_opens_a_4d_file_at_its_first_frame(tmp_path):
    """The GUI reads through :func:`splineviz.model.opening.read_file` in a job and shows
    the SplinevizWarnings it notes: a 4-D file opens (first frame) with the notice."""
    from splineviz.model.opening import noting_warnings, read_file

    data = np.random.default_rng(5).random((6, 5, 4, 3)).astype(np.float32)
    img = nib.Nifti1Image(data, np.eye(4))
    img.header.set_xyzt_units("mm", "msec")
    nib.save(img, tmp_path / "fmri.nii.gz")
    noted = noting_warnings(read_file, tmp_path / "fmri.nii.gz")
    kind, vol, _ = noted.value
    assert kind == "volume"
    np.testing.assert_array_equal(vol.data, data[..., 0])
    assert noted.warnings == ["fmri.nii.gz holds 3 frames along its time axis (the first is "
                              "shown; read_volume_sequence reads them all)"]
