"""Bad-input corpus: every case is generated here and must fail with a specific, typed,
one-sentence error; the CLI must answer it with exit code 2 and one line on stderr; failed
writes must leave no file behind.

Each case builder gets a fresh folder and returns ``(call, expected error class)``.
"""

import gzip
import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import splineviz as sv
from splineviz import cli
from splineviz.core.errors import SplinevizError
from splineviz.io import errors as E
from splineviz.io.session import load_session

FIELD = (np.arange(6 * 5 * 4, dtype=np.float32).reshape(6, 5, 4) % 17)
BIG = 10**6  # samples per axis of "absurd" headers: 10^18 samples


def _vol(d, name):
    sv.write_volume(d / name, sv.Volume(FIELD, spacing=(1, 2, 3)))
    return d / name


def _truncate(p, keep=0.5):
    data = p.read_bytes()
    p.write_bytes(data[: int(len(data) * keep)])
    return p


def _flip_bytes(p, start_frac=0.6, n=64):
    data = bytearray(p.read_bytes())
    s = int(len(data) * start_frac)
    data[s:s + n] = bytes((b ^ 0x5A) for b in data[s:s + n])
    p.write_bytes(bytes(data))
    return p


def _legacy(d, dims=(6, 5, 4), payload=None, dataset="STRUCTURED_POINTS"):
    n = int(np.prod(dims))
    body = payload if payload is not None else FIELD.astype(">f4").ravel(order="F").tobytes()
    head = (f"# vtk DataFile Version 3.0\ncorpus\nBINARY\nDATASET {dataset}\nDIMENSIONS "
            f"{dims[0]} {dims[1]} {dims[2]}\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA {n}\n"
            "SCALARS s float\nLOOKUP_TABLE default\n")
    (d / "v.vtk").write_bytes(head.encode() + body)
    return d / "v.vtk"


def _mhd(d, dims="6 5 4", datafile="v.raw", raw=True, etype="MET_FLOAT", compressed=False):
    (d / "v.mhd").write_text(f"ObjectType = Image\nNDims = 3\nDimSize = {dims}\n"
                             f"ElementType = {etype}\nCompressedData = "
                             f"{'True' if compressed else 'False'}\n"
                             f"ElementDataFile = {datafile}\n")
    if raw is True:
        (d / datafile).write_bytes(FIELD.astype("<f4").ravel(order="F").tobytes())
    elif raw is not None:
        (d / datafile).write_bytes(raw)
    return d / "v.mhd"


def _nrrd_text(d, header, payload=b"", name="v.nrrd"):
    (d / name).write_bytes(header.encode() + b"\n" + payload)
    return d / name


def _npy(d, arr, name="v.npy"):
    np.save(d / name, arr)
    return d / name


def _mrc(d, dims=(6, 5, 4)):
    import mrcfile

    with mrcfile.new(d / "m.mrc") as m:
        m.set_data(FIELD.transpose(2, 1, 0).copy())
    if dims != (6, 5, 4):
        data = bytearray((d / "m.mrc").read_bytes())
        data[0:12] = struct.pack("<3i", *dims)
        (d / "m.mrc").write_bytes(bytes(data))
    return d / "m.mrc"


def _slc(d):
    import vtk

    src = (Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "volumes" /
           "neghip.slc")
    if not src.exists():  # fall back to a header only
        (d / "v.slc").write_bytes(b"11111 66 66 66 8\n1.0 1.0 1.0\n")
        return d / "v.slc"
    (d / "v.slc").write_bytes(src.read_bytes())
    del vtk
    return d / "v.slc"


def _dicom(d, zs):
    sys.path.insert(0, str(Path(__file__).parent))
    try:
        from test_io_formats import _dicom_slice
    finally:
        sys.path.pop(0)
    for n, z in enumerate(zs):
        _dicom_slice(d / f"s{n}.dcm", np.full((3, 4), n, np.uint16), z, instance=n)
    return d


def _ply(d, n=10, text=False, count=None, body=None):
    from plyfile import PlyData, PlyElement

    v = np.zeros(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    v["x"], v["y"], v["z"] = np.random.default_rng(1).normal(size=(3, n))
    PlyData([PlyElement.describe(v, "vertex")], text=text).write(str(d / "c.ply"))
    if count is not None:
        data = (d / "c.ply").read_bytes().replace(f"element vertex {n}".encode(),
                                                  f"element vertex {count}".encode())
        (d / "c.ply").write_bytes(data)
    return d / "c.ply"


def _xyz(d, arr_or_text):
    p = d / "c.xyz"
    if isinstance(arr_or_text, str):
        p.write_text(arr_or_text)
    else:
        np.savetxt(p, arr_or_text)
    return p


def _pcd(d, points="3", data="ascii", body="0 0 0\n1 0 0\n"):
    p = d / "c.pcd"
    p.write_text("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                 f"COUNT 1 1 1\nWIDTH {points}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                 f"POINTS {points}\nDATA {data}\n{body}")
    return p


def _session(d, doc, name="s.svs"):
    p = d / name
    p.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    (d / "v.npy").exists() or np.save(d / "v.npy", FIELD)
    return p


def _doc(**over):
    doc = {"format": "splineviz-session", "schema_version": 2,
           "objects": [{"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
                       {"id": "i", "type": "Isosurface", "inputs": ["v"],
                        "properties": {"isovalue": 3.0}}]}
    doc.update(over)
    return doc


def _iso(**props):
    return _doc(objects=[{"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
                         {"id": "i", "type": "Isosurface", "inputs": ["v"],
                          "properties": {"isovalue": 3.0, **props}}])


RV, RP, LS = sv.read_volume, sv.read_points, load_session

CASES = {
    # ------------------------------------------------------------------ volumes
    "vti-truncated": lambda d: (lambda: RV(_truncate(_vol(d, "v.vti"))), E.CorruptFileError),
    "vti-corrupt-zlib": lambda d: (lambda: RV(_flip_bytes(_vol(d, "v.vti"), 0.8, 16)),
                                   E.CorruptFileError),
    "vti-wrong-type": lambda d: ((d / "v.vti").write_text(
        '<?xml version="1.0"?><VTKFile type="PolyData" version="1.0"><PolyData>'
        '</PolyData></VTKFile>'), (lambda: RV(d / "v.vti"), E.CorruptFileError))[1],
    "vti-empty-file": lambda d: ((d / "v.vti").write_bytes(b""),
                                 (lambda: RV(d / "v.vti"), E.CorruptFileError))[1],
    "vtk-truncated": lambda d: (lambda: RV(_truncate(_legacy(d), 0.8)), E.CorruptFileError),
    "vtk-dims-exceed-payload": lambda d: (lambda: RV(_legacy(d, dims=(60, 5, 4))),
                                          E.CorruptFileError),
    "vtk-polydata-not-image": lambda d: (lambda: RV(_legacy(d, dataset="POLYDATA")),
                                         E.FileFormatError),
    "slc-truncated": lambda d: (lambda: RV(_truncate(_slc(d), 0.3)), E.CorruptFileError),
    "slc-garbage-header": lambda d: ((d / "v.slc").write_bytes(b"11111 x y z\n\x00\x01"),
                                     (lambda: RV(d / "v.slc"), E.CorruptFileError))[1],
    "mhd-missing-payload": lambda d: (lambda: RV(_mhd(d, raw=None)), E.DataFileNotFoundError),
    "mhd-short-payload": lambda d: (lambda: RV(_mhd(d, raw=b"\0" * 40)), E.DataSizeError),
    "mhd-absurd-dims": lambda d: (lambda: RV(_mhd(d, dims=f"{BIG} {BIG} {BIG}")),
                                  E.DataTooLargeError),
    "mhd-corrupt-zraw": lambda d: (lambda: RV(_mhd(d, datafile="v.zraw", raw=b"\x78\x9c" +
                                                   b"junk" * 50, compressed=True)),
                                   E.CorruptFileError),
    "nrrd-truncated": lambda d: (lambda: RV(_nrrd_text(
        d, "NRRD0004\ntype: float\ndimension: 3\nsizes: 6 5 4\nencoding: raw\nendian: little\n",
        FIELD.astype("<f4").tobytes()[:100])), E.CorruptFileError),
    "nrrd-corrupt-gzip": lambda d: (lambda: RV(_nrrd_text(
        d, "NRRD0004\ntype: float\ndimension: 3\nsizes: 6 5 4\nencoding: gzip\nendian: little\n",
        gzip.compress(FIELD.tobytes())[:30] + b"\xff" * 30)), E.CorruptFileError),
    "nrrd-bad-type": lambda d: (lambda: RV(_nrrd_text(
        d, "NRRD0004\ntype: banana\ndimension: 3\nsizes: 6 5 4\nencoding: raw\n", b"\0" * 480)),
        E.CorruptFileError),
    "nrrd-absurd-sizes": lambda d: (lambda: RV(_nrrd_text(
        d, f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {BIG} {BIG} {BIG}\nencoding: raw\n")),
        E.DataTooLargeError),
    "nrrd-2d-image": lambda d: (lambda: RV(_nrrd_text(
        d, "NRRD0004\ntype: uint8\ndimension: 2\nsizes: 4 4\nencoding: raw\n", b"\0" * 16)),
        E.InvalidDataError),
    "nrrd-datafile-is-a-device": lambda d: (lambda: RV(_nrrd_text(
        d, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 3\nencoding: raw\n"
           "data file: /dev/zero\n", name="v.nhdr")), E.OutsideFolderError),
    "mhd-datafile-is-a-device": lambda d: (lambda: RV(_mhd(d, datafile="/dev/zero", raw=None)),
                                           E.OutsideFolderError),
    "nhdr-missing-slice": lambda d: (lambda: RV(_nrrd_text(
        d, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 3\nencoding: raw\n"
           "data file: s.%d 1 3 1\n", name="v.nhdr")), E.DataFileNotFoundError),
    "nifti-truncated": lambda d: (lambda: RV(_truncate(_nifti(d), 0.7)), E.CorruptFileError),
    "nifti-garbage-gz": lambda d: ((d / "v.nii.gz").write_bytes(b"\x1f\x8b" + b"\0" * 50),
                                   (lambda: RV(d / "v.nii.gz"), E.CorruptFileError))[1],
    "mrc-truncated": lambda d: (lambda: RV(_truncate(_mrc(d), 0.7)), E.CorruptFileError),
    "mrc-absurd-dims": lambda d: (lambda: RV(_mrc(d, dims=(BIG, BIG, BIG))),
                                  E.DataTooLargeError),
    "mrc-negative-dims": lambda d: (lambda: RV(_mrc(d, dims=(-5, 5, 4))), SplinevizError),
    "npy-truncated": lambda d: (lambda: RV(_truncate(_npy(d, FIELD), 0.6)), E.CorruptFileError),
    "npy-pickled-objects": lambda d: (
        np.save(d / "o.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True),
        (lambda: RV(d / "o.npy"), E.CorruptFileError))[1],
    "npy-2d": lambda d: (lambda: RV(_npy(d, np.zeros((4, 4)))), E.InvalidDataError),
    "npy-zero-size": lambda d: (lambda: RV(_npy(d, np.zeros((0, 4, 4)))), E.InvalidDataError),
    "npy-one-voxel": lambda d: (lambda: RV(_npy(d, np.zeros((1, 1, 1)))), E.InvalidDataError),
    "npy-all-nan": lambda d: (lambda: RV(_npy(d, np.full((3, 3, 3), np.nan))),
                              E.InvalidDataError),
    "npy-inf-samples": lambda d: (lambda: RV(_npy(d, np.where(FIELD > 15, np.inf, FIELD))),
                                  E.InvalidDataError),
    "npy-complex": lambda d: (lambda: RV(_npy(d, np.zeros((3, 3, 3), complex))),
                              E.InvalidDataError),
    "raw-size-mismatch": lambda d: ((d / "v.raw").write_bytes(b"\0" * 100),
                                    (lambda: RV(d / "v.raw", dims=(6, 5, 4), dtype="uint8"),
                                     E.DataSizeError))[1],
    "raw-absurd-dims": lambda d: ((d / "v.raw").write_bytes(b"\0" * 100),
                                  (lambda: RV(d / "v.raw", dims=(BIG,) * 3, dtype="float64"),
                                   E.DataTooLargeError))[1],
    "raw-without-dims": lambda d: ((d / "v.raw").write_bytes(b"\0" * 100),
                                   (lambda: RV(d / "v.raw"), E.FileFormatError))[1],
    "dicom-empty-folder": lambda d: (lambda: RV(d), E.InvalidDataError),
    "dicom-one-slice": lambda d: (lambda: RV(_dicom(d, [0.0])), E.InvalidDataError),
    "dicom-same-position": lambda d: (lambda: RV(_dicom(d, [0.0, 1.0, 1.0])),
                                      E.InvalidDataError),
    "unknown-format": lambda d: ((d / "x.zzz").write_bytes(os.urandom(300)),
                                 (lambda: RV(d / "x.zzz"), E.UnknownFormatError))[1],
    "missing-file": lambda d: (lambda: RV(d / "nope.vti"), E.DataFileNotFoundError),
    "special-file": lambda d: (os.mkfifo(d / "fifo.vti"),
                               (lambda: RV(d / "fifo.vti"), E.DataFileNotFoundError))[1],
    # ------------------------------------------------------------------ points
    "ply-truncated-binary": lambda d: (lambda: RP(_truncate(_ply(d, 100), 0.7)),
                                       E.CorruptFileError),
    "ply-bad-header": lambda d: ((d / "c.ply").write_bytes(b"ply\nformat banana 1.0\n"
                                                           b"end_header\n"),
                                 (lambda: RP(d / "c.ply"), E.CorruptFileError))[1],
    "ply-absurd-count": lambda d: (lambda: RP(_ply(d, 10, count=10**12)), E.CorruptFileError),
    "ply-empty": lambda d: (lambda: RP(_ply(d, 0)), E.InvalidDataError),
    "ply-no-vertices": lambda d: ((d / "c.ply").write_bytes(
        b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\n"
        b"end_header\n"), (lambda: RP(d / "c.ply"), E.InvalidDataError))[1],
    "xyz-empty": lambda d: (lambda: RP(_xyz(d, "# nothing here\n")), E.InvalidDataError),
    "xyz-four-columns": lambda d: (lambda: RP(_xyz(d, np.ones((5, 4)))), E.CorruptFileError),
    "xyz-not-numbers": lambda d: (lambda: RP(_xyz(d, "1 2 3\na b c\n")), E.CorruptFileError),
    "xyz-nan": lambda d: (lambda: RP(_xyz(d, "1 2 3\nnan 0 0\n0 1 0\n")), E.InvalidDataError),
    "xyz-all-duplicates": lambda d: (lambda: RP(_xyz(d, np.ones((50, 3)))),
                                     E.InvalidDataError),
    "xyz-collinear": lambda d: (lambda: RP(_xyz(d, np.outer(np.arange(20.0), (1, 2, 3)))),
                                E.InvalidDataError),
    "xyz-binary-junk": lambda d: ((d / "c.xyz").write_bytes(b"\0\1\2" * 100),
                                  (lambda: RP(d / "c.xyz"), E.CorruptFileError))[1],
    "pcd-truncated": lambda d: (lambda: RP(_pcd(d)), E.CorruptFileError),
    "pcd-absurd-count": lambda d: (lambda: RP(_pcd(d, points=str(10**11), data="binary",
                                                   body="0123")), E.DataSizeError),
    "pcd-no-header": lambda d: ((d / "c.pcd").write_text("1 2 3\n"),
                                (lambda: RP(d / "c.pcd"), E.CorruptFileError))[1],
    "off-truncated": lambda d: ((d / "c.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n"),
                                (lambda: RP(d / "c.off"), E.CorruptFileError))[1],
    "off-absurd-count": lambda d: ((d / "c.off").write_text("OFF\n30000000000 1 0\n0 0 0\n"),
                                   (lambda: RP(d / "c.off"), E.DataSizeError))[1],
    "stl-truncated": lambda d: (lambda: RP(_truncate(_stl(d), 0.6)), SplinevizError),
    "obj-no-vertices": lambda d: ((d / "c.obj").write_text("# nothing\nf 1 2 3\n"),
                                  (lambda: RP(d / "c.obj"), SplinevizError))[1],
    # ------------------------------------------------------------------ sessions
    "session-not-json": lambda d: (lambda: LS(_session(d, "{not json")), E.SessionError),
    "session-top-level-list": lambda d: (lambda: LS(_session(d, "[]")), E.SessionError),
    "session-wrong-format": lambda d: (lambda: LS(_session(d, _doc(format="paraview"))),
                                       E.SessionError),
    "session-future-version": lambda d: (lambda: LS(_session(d, _doc(schema_version=99))),
                                         E.SessionVersionError),
    "session-unknown-old-version": lambda d: (lambda: LS(_session(d, _doc(schema_version=0))),
                                              E.SessionVersionError),
    "session-version-string": lambda d: (lambda: LS(_session(d, _doc(schema_version="2"))),
                                         E.SessionVersionError),
    "session-absolute-path-outside": lambda d: (lambda: LS(_session(d, _doc(objects=[
        {"id": "v", "type": "VolumeFile", "properties": {"path": "/etc/passwd"}}]))),
        E.SessionPathError),
    "session-fifo-path": lambda d: (os.mkfifo(d / "pipe.npy"), (lambda: LS(_session(d, _doc(
        objects=[{"id": "v", "type": "VolumeFile", "properties": {"path": "pipe.npy"}}]))),
        E.SessionPathError))[1],
    "session-wrong-type": lambda d: (lambda: LS(_session(d, _iso(isovalue="abc"))),
                                     E.SessionError),
    "session-huge-float": lambda d: (lambda: LS(_session(d, '{"format": "splineviz-session", '
                                                         '"schema_version": 2, "objects": [{"id"'
                                                         ': "s", "type": "ClipPlane", "propert'
                                                         'ies": {"origin": [1e400, 0, 0]}}]}')),
                                     E.SessionError),
    "session-huge-integer": lambda d: (lambda: LS(_session(d, '{"format": "splineviz-session",'
                                                           ' "schema_version": ' + "9" * 5000 +
                                                           "}")), E.SessionError),
    "session-deep-nesting": lambda d: (lambda: LS(_session(d, "[" * 100000 + "]" * 100000)),
                                       E.SessionError),
    "session-nan-literal": lambda d: (lambda: LS(_session(d, json.dumps(_iso()).replace(
        "3.0", "NaN"))), E.SessionError),
    "session-duplicate-keys": lambda d: (lambda: LS(_session(
        d, '{"format": "splineviz-session", "format": "x", "schema_version": 2}')),
        E.SessionError),
    "session-unknown-key": lambda d: (lambda: LS(_session(d, _iso(code="__import__('os')"))),
                                      E.SessionError),
    "session-forward-input": lambda d: (lambda: LS(_session(d, _doc(objects=[
        {"id": "i", "type": "Isosurface", "inputs": ["v"], "properties": {"isovalue": 1}},
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}}]))), E.SessionError),
    "session-duplicate-ids": lambda d: (lambda: LS(_session(d, _doc(objects=[
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
        {"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}}]))), E.SessionError),
    "session-opacity-out-of-range": lambda d: (lambda: LS(_session(d, _iso(opacity=7))),
                                               E.SessionError),
    "session-degenerate-camera": lambda d: (lambda: LS(_session(d, _doc(views=[
        {"id": "v", "camera": {"position": [1, 2, 3], "focal_point": [1, 2, 3]}}]))),
        E.SessionError),
    "session-too-large": lambda d: (lambda: LS(_session(d, " " * (17 * 2**20) + "{}")),
                                    E.SessionError),
    "session-not-utf8": lambda d: ((d / "s.svs").write_bytes(b"\xff\xfe{\x00}"),
                                   (lambda: LS(d / "s.svs"), E.SessionError))[1],
    "session-unknown-source": lambda d: (lambda: LS(_session(d, _doc(objects=[
        {"id": "s", "type": "Source", "properties": {"source": "no-such-source"}}]))),
        E.SessionError),
    # ------------------------------------------------------------------ writers
    "write-into-missing-folder": lambda d: (lambda: sv.write_mesh(
        d / "no" / "m.ply", _tet()), E.WriteError),
    "write-unknown-suffix": lambda d: (lambda: sv.write_mesh(d / "m.xyz9", _tet()),
                                       E.UnknownFormatError),
    "write-faces-out-of-range": lambda d: (lambda: sv.write_mesh(
        d / "m.ply", (_tet()[0], [[0, 1, 9]])), E.InvalidDataError),
    "write-bad-screenshot": lambda d: (lambda: sv.write_screenshot(
        d / "s.png", np.zeros((4, 4), np.float32)), E.InvalidDataError),
}


def _nifti(d):
    import nibabel as nib

    nib.save(nib.Nifti1Image(FIELD, np.eye(4)), d / "v.nii")
    return d / "v.nii"


def _stl(d):
    import pyvista as pv

    sv.write_mesh(d / "c.stl", pv.Icosphere(nsub=1))
    return d / "c.stl"


def _tet():
    return (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float),
            np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]))


def test_corpus_is_big_enough():
    assert len(CASES) >= 40


@pytest.mark.parametrize("case", sorted(CASES))
def test_corpus_case_gives_one_typed_sentence(case, tmp_path):
    call, expected = CASES[case](tmp_path)
    with pytest.raises(expected) as info:
        call()
    msg = str(info.value)
    assert isinstance(info.value, SplinevizError)
    assert msg and "\n" not in msg and len(msg) < 400, msg
    assert "Traceback" not in msg
    # no temporary or half-written output is left behind
    names = [p.name for p in tmp_path.rglob("*")]
    assert not [n for n in names if ".part" in n], names
    if case.startswith("write-"):
        assert not {"m.ply", "m.xyz9", "s.png"} & set(names), names


FILE_CASES = [c for c in sorted(CASES) if not c.startswith(("write-", "raw-", "dicom-"))]


@pytest.mark.parametrize("case", FILE_CASES)
def test_cli_info_answers_one_line_and_exit_2(case, tmp_path, capsys):
    """``splineviz info`` on the corpus file: exit code 2 and exactly one line on stderr."""
    call, _ = CASES[case](tmp_path)
    # the corpus file is the newest regular file (or the folder itself for DICOM)
    files = [p for p in tmp_path.iterdir() if p.suffix not in (".raw", ".zraw") and
             not p.name.startswith("v.npy") or p.name == "v.npy"]
    target = _target_of(case, tmp_path, files)
    rc = cli.main(["info", str(target)])
    out, err = capsys.readouterr()
    assert rc == 2, (case, out)
    assert len(err.strip().splitlines()) == 1 and err.startswith("splineviz: error: "), err


def _target_of(case, d, files):
    if case == "missing-file":
        return d / "nope.vti"
    if case.startswith("session-"):
        return d / "s.svs"
    for name in ("v.vti", "v.vtk", "v.slc", "v.mhd", "v.nrrd", "v.nhdr", "v.nii", "v.nii.gz",
                 "m.mrc", "o.npy", "c.ply", "c.xyz", "c.pcd", "c.off", "c.stl", "c.obj",
                 "x.zzz", "fifo.vti"):
        if (d / name).exists() or (d / name).is_fifo():
            return d / name
    return d / "v.npy"


def test_cli_in_a_subprocess_prints_no_traceback(tmp_path):
    (tmp_path / "bad.nrrd").write_bytes(b"NRRD0004\ntype: banana\n")
    r = subprocess.run([sys.executable, "-m", "splineviz.cli", "info", str(tmp_path / "bad.nrrd")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr, r.stderr
