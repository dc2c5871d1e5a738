"""Every hostile case of issue 16 reproduced: a one-sentence SplinevizError (or a documented
acceptance with a SplinevizWarning), never a traceback, a hang or silent garbage; files named
by headers and sessions stay in their folder unless the caller opts in."""

import json
import os
import time
import tracemalloc
import warnings

import numpy as np
import pytest

import splineviz as sv
from splineviz import cli
from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.io import errors as E
from splineviz.io.session import Session, load_session, save_session

F = (np.arange(5 * 4 * 3, dtype=np.float32).reshape(5, 4, 3) % 7)
RAW = F.astype("<f4").ravel(order="F").tobytes()


def _mhd(d, datafile, name="v.mhd", extra=""):
    (d / name).write_text("ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\n"
                          f"ElementType = MET_FLOAT\n{extra}ElementDataFile = {datafile}\n")
    return d / name


def _one_sentence(exc):
    msg = str(exc)
    assert isinstance(exc, SplinevizError) and msg and "\n" not in msg and len(msg) <= 300
    return msg


# ---------------------------------------------------------------------------- security
@pytest.fixture
def nest(tmp_path):
    """``tmp/sub`` holds the headers; ``tmp/outside.raw`` is a valid payload outside it."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "outside.raw").write_bytes(RAW)
    return tmp_path


@pytest.mark.parametrize("name", ["/etc/passwd", "../outside.raw", "LINK"])
def test_metaimage_data_file_outside_its_folder_is_refused(nest, name):
    if name == "LINK":
        os.symlink(nest / "outside.raw", nest / "sub" / "link.raw")
        name = "link.raw"
    hdr = _mhd(nest / "sub", name)
    with pytest.raises(E.OutsideFolderError) as info:
        sv.read_volume(hdr)
    msg = _one_sentence(info.value)
    assert "v.mhd" in msg and "outside" in msg
    assert info.value.path.is_absolute() and info.value.folder == (nest / "sub").resolve()


def test_the_opt_in_reads_outside_data(nest):
    hdr = _mhd(nest / "sub", "../outside.raw")
    vol = sv.read_volume(hdr, allow_outside=True)
    np.testing.assert_array_equal(vol.data, F)
    assert cli.main(["info", "--allow-outside-data", str(hdr)]) == 0


def test_data_inside_the_folder_still_reads(nest):
    (nest / "sub" / "in.raw").write_bytes(RAW)
    np.testing.assert_array_equal(sv.read_volume(_mhd(nest / "sub", "in.raw")).data, F)


@pytest.mark.parametrize("datafile", ["../outside.raw", "/etc/passwd", "../s%d.raw 0 2 1 2"])
def test_nrrd_data_file_outside_its_folder_is_refused(nest, datafile):
    (nest / "sub" / "v.nhdr").write_text("NRRD0004\ntype: float\ndimension: 3\nsizes: 5 4 3\n"
                                         f"encoding: raw\nendian: little\ndata file: {datafile}\n")
    with pytest.raises(E.OutsideFolderError):
        sv.read_volume(nest / "sub" / "v.nhdr")


def test_nrrd_list_names_are_confined(nest):
    (nest / "sub" / "v.nhdr").write_text("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n"
                                         "encoding: raw\ndata file: LIST\n../a.raw\n../b.raw\n")
    # pynrrd refuses LIST headers as malformed before any name is looked at; either way no
    # file outside is opened
    with pytest.raises((E.OutsideFolderError, E.CorruptFileError)):
        sv.read_volume(nest / "sub" / "v.nhdr")


@pytest.mark.parametrize("how", ["dotdot", "symlink", "absolute"])
def test_session_data_outside_its_folder_is_refused(nest, how):
    np.save(nest / "v.npy", F)
    path = {"dotdot": "../v.npy", "symlink": "link.npy", "absolute": "/etc/passwd"}[how]
    if how == "symlink":
        os.symlink("/etc/passwd", nest / "sub" / "link.npy")
    doc = {"format": "splineviz-session", "schema_version": 3,
           "objects": [{"id": "v", "type": "VolumeFile", "properties": {"path": path}}]}
    (nest / "sub" / "s.svs").write_text(json.dumps(doc))
    with pytest.raises(E.SessionOutsideFolderError) as info:
        load_session(nest / "sub" / "s.svs")
    _one_sentence(info.value)
    assert isinstance(info.value, E.SessionPathError)  # what GUIs caught before
    with pytest.raises(E.SessionOutsideFolderError):
        load_session(nest / "sub" / "s.svs", check_data=False)  # info reads no data, still
    if how == "dotdot":  # the GUI's retry after the user confirmed
        s = load_session(nest / "sub" / "s.svs", allow_outside=True)
        np.testing.assert_array_equal(s.load_volume("v").data, F)


def test_cli_refuses_outside_data_in_one_line(nest, capsys):
    hdr = _mhd(nest / "sub", "/etc/passwd")
    assert cli.main(["render", str(hdr), "-o", str(nest / "o.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "/etc/passwd" in err
    assert not (nest / "o.png").exists()


# ---------------------------------------------------------------------------- crashes
@pytest.mark.parametrize("objects", [5, None, "x"])
def test_schema1_session_with_bad_objects(tmp_path, objects, capsys):
    (tmp_path / "s.svs").write_text(json.dumps(
        {"format": "splineviz-session", "schema_version": 1, "objects": objects}))
    with pytest.raises(E.SessionError) as info:
        load_session(tmp_path / "s.svs")
    assert "objects" in _one_sentence(info.value)
    assert cli.main(["info", str(tmp_path / "s.svs")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.parametrize("kwargs", [{"model": "nope"}, {"model": "to-quadratic", "k": 0},
                                    {"model": "to-quadratic", "k": -1},
                                    {"model": "to-quadratic", "k": float("nan")},
                                    {"model": "cubic-c1", "k": 2}])
def test_build_spline_bad_model_or_option(kwargs):
    with pytest.raises(SplinevizError) as info:
        sv.build_spline(sv.Volume(F), **kwargs)
    assert isinstance(info.value, ValueError)  # still what generic handlers catch
    _one_sentence(info.value)


def test_save_session_onto_a_directory(tmp_path):
    (tmp_path / "s.svs").mkdir()
    with pytest.raises(E.WriteError, match="folder"):
        save_session(Session(), tmp_path / "s.svs")
    assert [p.name for p in tmp_path.iterdir()] == ["s.svs"]


@pytest.mark.parametrize("size", ["100000x100000", "16385x10", "0x10", "10x"])
def test_absurd_render_size_is_refused_before_anything_is_read(tmp_path, size, capsys):
    np.save(tmp_path / "v.npy", F)
    assert cli.main(["render", str(tmp_path / "v.npy"), "--size", size, "-o",
                     str(tmp_path / "o.png")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_raycaster_refuses_a_frame_the_device_cannot_hold(monkeypatch):
    """Checked against the device's limits before any buffer exists: a device with 1 GiB
    (256 MiB per buffer) is simulated, so nothing is allocated whatever the real device."""
    from types import SimpleNamespace

    from splineviz.compute.raycast import RayCaster, RayCastError

    rc = RayCaster(sv.Volume(F), "trilinear", device="numpy")
    rc.set_isovalue(3.0)
    small = SimpleNamespace(name="a 1 GiB device", device=SimpleNamespace(
        max_mem_alloc_size=2**28, global_mem_size=2**30))
    monkeypatch.setattr(rc, "_device", small)
    with pytest.raises(RayCastError, match="8192x8192 frame") as info:
        rc.render(sv.Camera((20, 20, 20), (2, 2, 1)), (8192, 8192))
    _one_sentence(info.value)
    rc._check_frame_memory(1024, 768)  # an ordinary frame fits


@pytest.mark.parametrize("iso", ["nan", "inf", "-inf"])
def test_nonfinite_isovalue_is_a_usage_error(tmp_path, iso, capsys):
    np.save(tmp_path / "v.npy", F)
    assert cli.main(["render", str(tmp_path / "v.npy"), f"--iso={iso}", "-o",
                     str(tmp_path / "o.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "finite" in err


@pytest.mark.parametrize("n", [4, 6, 10, 20])
def test_remesh_of_too_few_points(n):
    from splineviz.pointcloud.remesh import RemeshError, remesh

    pts = np.random.default_rng(n).normal(size=(n, 3))
    with pytest.raises(RemeshError, match="at least"):
        remesh(pts)


def test_remesh_of_a_colinear_cloud():
    from splineviz.pointcloud.remesh import RemeshError, remesh

    t = np.linspace(0, 1, 200)
    pts = np.c_[t, 2 * t, 3 * t] + np.random.default_rng(0).normal(scale=1e-6, size=(200, 3))
    with pytest.raises(RemeshError, match="line"):
        remesh(pts)


# ---------------------------------------------------------------------------- hangs
def _fast_and_small(call, expected):
    tracemalloc.start()
    t = time.perf_counter()
    try:
        with pytest.raises(expected) as info:
            call()
    finally:
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    seconds = time.perf_counter() - t
    assert seconds < 10.0 and peak < 200 * 2**20, (seconds, peak)
    return _one_sentence(info.value)


@pytest.mark.parametrize("datafile", ["s%d.raw 1 400000000 1 2", "s%d.raw 1 4000000000000 1",
                                      "s%0999999999d.raw 1 3 1 2", "s%.999999999d.raw 1 3 1",
                                      "s%d%d.raw 1 3 1", "s%s.raw 1 3 1", "s%n.raw 1 3 1"])
def test_nrrd_pattern_bombs_are_refused_fast(tmp_path, datafile):
    (tmp_path / "v.nhdr").write_text("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 3\n"
                                     f"encoding: raw\ndata file: {datafile}\n")
    _fast_and_small(lambda: sv.read_volume(tmp_path / "v.nhdr"), E.CorruptFileError)


def test_metaimage_pattern_bomb_is_refused_fast(tmp_path):
    _mhd(tmp_path, "s%d.raw 1 400000000 1")
    _fast_and_small(lambda: sv.read_volume(tmp_path / "v.mhd"), E.CorruptFileError)


@pytest.mark.parametrize("where", ["first", "last"])
def test_duplicate_key_check_is_linear(tmp_path, where):
    n = 60_000
    keys = ",".join(f'"k{i}":1' for i in range(n))
    dup = "k0" if where == "first" else f"k{n - 1}"
    (tmp_path / "s.svs").write_text('{"format":"splineviz-session","schema_version":3,"x":{'
                                    + keys + f',"{dup}":2}}}}')
    msg = _fast_and_small(lambda: load_session(tmp_path / "s.svs"), E.SessionError)
    assert dup in msg


@pytest.mark.parametrize("name", ["f.nrrd", "f.unknown", "f.svs", "f.ply"])
def test_a_fifo_is_refused_without_blocking(tmp_path, name):
    from splineviz.io.opening import open_path
    from splineviz.io.registry import read_head

    os.mkfifo(tmp_path / name)
    _fast_and_small(lambda: open_path(tmp_path / name), SplinevizError)
    with pytest.raises(E.DataFileNotFoundError):  # the sniffer itself never waits
        read_head(tmp_path / name)


def test_a_fifo_named_by_a_header_is_refused(tmp_path):
    os.mkfifo(tmp_path / "pipe.raw")
    _fast_and_small(lambda: sv.read_volume(_mhd(tmp_path, "pipe.raw")),
                    E.DataFileNotFoundError)


# ---------------------------------------------------------------------------- garbage
def test_nan_volume_builds_no_spline():
    data = F.copy()
    data[1, 1, 1] = np.nan
    with pytest.raises(sv.VolumeError, match="NaN"):
        sv.build_spline(sv.Volume(data), "cubic-c1")
    with pytest.raises(sv.VolumeError, match="NaN"):
        sv.build_spline(sv.Volume(np.full((3, 3, 3), np.nan)), "trilinear")


def test_nan_samples_refused_or_filled_with_a_warning(tmp_path):
    data = F.copy()
    data[0, 0, 0], data[1, 2, 0] = np.nan, np.inf
    np.save(tmp_path / "v.npy", data)
    with pytest.raises(E.InvalidDataError, match="2 NaN or infinite"):
        sv.read_volume(tmp_path / "v.npy")
    with pytest.warns(SplinevizWarning, match="2 NaN or infinite samples were replaced by 0"):
        vol = sv.read_volume(tmp_path / "v.npy", nonfinite="fill")
    assert np.isfinite(vol.data).all() and vol.data[0, 0, 0] == 0


def test_all_nan_volume_is_refused(tmp_path):
    np.save(tmp_path / "v.npy", np.full((3, 3, 3), np.nan, np.float32))
    with pytest.raises(E.InvalidDataError, match="no finite"):
        sv.read_volume(tmp_path / "v.npy", nonfinite="fill")


@pytest.mark.parametrize("dtype", [np.complex64, np.complex128])
def test_complex_samples_are_refused(tmp_path, dtype):
    np.save(tmp_path / "v.npy", F.astype(dtype))
    with pytest.raises(E.InvalidDataError, match="complex"):
        sv.read_volume(tmp_path / "v.npy")


def test_complex_nifti_is_refused(tmp_path):
    import nibabel as nib

    nib.save(nib.Nifti1Image(F.astype(np.complex64), np.eye(4)), tmp_path / "v.nii")
    with pytest.raises(E.InvalidDataError, match="complex"):
        sv.read_volume(tmp_path / "v.nii")


def test_float64_beyond_float32_is_not_called_infinite(tmp_path):
    data = F.astype(np.float64)
    data[2, 2, 2] = 1e300
    np.save(tmp_path / "v.npy", data)
    with pytest.raises(E.InvalidDataError, match="beyond the float32 range") as info:
        sv.read_volume(tmp_path / "v.npy")
    assert "infinite" not in str(info.value)


def test_negative_metaimage_spacing_flips_the_axis_with_a_warning(tmp_path):
    (tmp_path / "v.mha").write_bytes(
        b"ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementSpacing = -1 2 3\n"
        b"Offset = 10 0 0\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n" + RAW)
    with pytest.warns(SplinevizWarning, match="negative spacing along x"):
        vol = sv.read_volume(tmp_path / "v.mha")
    assert vol.spacing == (1.0, 2.0, 3.0) and vol.origin == (6.0, 0.0, 0.0)
    # every sample keeps its world position: x = 10 - i in the file
    np.testing.assert_array_equal(vol.data, F[::-1])


def test_negative_nrrd_space_direction_flips_the_axis(tmp_path):
    import nrrd

    nrrd.write(str(tmp_path / "v.nrrd"), F, {"space dimension": 3,
                                            "space directions": np.diag([1.0, -2.0, 3.0]),
                                            "space origin": np.zeros(3)}, index_order="F")
    with pytest.warns(SplinevizWarning, match="along y"):
        vol = sv.read_volume(tmp_path / "v.nrrd")
    assert vol.spacing == (1.0, 2.0, 3.0) and vol.origin == (0.0, -6.0, 0.0)
    np.testing.assert_array_equal(vol.data, F[:, ::-1])


def test_cli_prints_documented_warnings_as_one_line(tmp_path, capsys):
    (tmp_path / "v.mha").write_bytes(
        b"ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementSpacing = 1 -2 3\n"
        b"ElementType = MET_FLOAT\nElementDataFile = LOCAL\n" + RAW)
    vol = str(tmp_path / "v.mha")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # main() shows ours as lines and drops the others
        assert cli.main(["render", vol, "--size", "32x24", "--device", "numpy", "-o",
                         str(tmp_path / "o.png")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert [ln for ln in err if ln.startswith("splineviz: warning:")] and \
        all(ln.startswith("splineviz:") for ln in err), err


# ---------------------------------------------------------------------------- the CLI
def _subprocess_cases(d):
    """A handful of representative refusals, run as a user runs them."""
    import nibabel as nib

    (d / "sub").mkdir()
    _mhd(d / "sub", "/etc/passwd")
    (d / "trunc.mha").write_bytes(b"ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\n"
                                  b"ElementType = MET_FLOAT\nElementDataFile = LOCAL\n" + RAW[:99])
    (d / "bomb.nhdr").write_text("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 3\n"
                                 "encoding: raw\ndata file: s%0999999999d.raw 1 3 1 2\n")
    nib.save(nib.Nifti1Image(F, np.eye(4)), d / "v.nii")
    (d / "trunc.nii").write_bytes((d / "v.nii").read_bytes()[:360])
    os.mkfifo(d / "pipe.nrrd")
    return [["info", str(d / "sub" / "v.mhd")],
            ["render", str(d / "trunc.mha"), "-o", str(d / "o.png")],
            ["info", str(d / "bomb.nhdr")],
            ["render", str(d / "trunc.nii"), "-o", str(d / "o.png")],
            ["info", str(d / "pipe.nrrd")]]


def test_cli_refusals_are_one_line_without_traceback(tmp_path, tried):
    import subprocess
    import sys

    for argv in _subprocess_cases(tmp_path):
        t = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "splineviz.cli", *argv], capture_output=True,
                           text=True, timeout=120, env={**os.environ, "DISPLAY": ""})
        assert r.returncode == 2, (argv, r.stdout, r.stderr)
        assert r.stderr.count("\n") == 1 and r.stderr.startswith("splineviz: error: "), \
            (argv, r.stderr)
        assert time.perf_counter() - t < 60
        tried["cli subprocess"] += 1
    assert not (tmp_path / "o.png").exists()
