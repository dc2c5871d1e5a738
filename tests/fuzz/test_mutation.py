"""Property-based mutation of every reader's valid files and of sessions.

Each format gets one small valid file (detached payloads included); hypothesis applies
byte mutations (truncate, flip, insert, zero), header edits (a number of the header replaced
by a hostile one: 0, -1, 2^32, 10^20, nan, 1e309...) and, for sessions, structural edits of
the JSON (a value anywhere replaced by a wrong type, a huge or hostile value, a path out of
the folder). Every mutant must read into finite data or raise one SplinevizError sentence:
never another exception, a hang or a file read outside the folder.

The default run is derandomized and small (CI-deterministic); ``-m slow`` runs many more.
"""

import copy
import json
import re
import time
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splineviz as sv
from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.io.session import load_session

F = ((np.arange(5 * 4 * 3, dtype=np.float32).reshape(5, 4, 3) % 7) - 2.5)
PTS = np.random.default_rng(3).normal(size=(12, 3))
#: longest a single mutant may take to read or be refused (the real ones take milliseconds)
SECONDS = 5.0


def _volume_file(kind, d):
    import mrcfile
    import nibabel as nib
    import pyvista as pv

    vol = sv.Volume(F, spacing=(1, 2, 3), origin=(4, 5, 6))
    raw = F.astype("<f4").ravel(order="F").tobytes()
    head = "ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementSpacing = 1 2 3\n" \
           "ElementType = MET_FLOAT\n"
    if kind in ("vti", "nrrd", "npy"):
        return sv.write_volume(d / f"v.{kind}", vol)
    if kind == "vtk":
        img = pv.ImageData(dimensions=F.shape)
        img.point_data["s"] = F.ravel(order="F")
        img.save(d / "v.vtk")
        return d / "v.vtk"
    if kind == "mha":
        (d / "v.mha").write_bytes((head + "ElementDataFile = LOCAL\n").encode() + raw)
        return d / "v.mha"
    if kind == "mhd":
        (d / "v.raw").write_bytes(raw)
        (d / "v.mhd").write_text(head + "ElementDataFile = v.raw\n")
        return d / "v.mhd"
    if kind == "mhd-zraw":
        import zlib

        (d / "v.zraw").write_bytes(zlib.compress(raw))
        (d / "v.mhd").write_text(head + "CompressedData = True\nElementDataFile = v.zraw\n")
        return d / "v.mhd"
    if kind == "nhdr":
        (d / "v.raw").write_bytes(raw)
        (d / "v.nhdr").write_text("NRRD0004\ntype: float\ndimension: 3\nsizes: 5 4 3\n"
                                  "spacings: 1 2 3\nencoding: raw\nendian: little\n"
                                  "data file: v.raw\n")
        return d / "v.nhdr"
    if kind == "nhdr-slices":
        for k in range(3):
            (d / f"s{k}.raw").write_bytes(F[:, :, k].astype("<f4").ravel(order="F").tobytes())
        (d / "v.nhdr").write_text("NRRD0004\ntype: float\ndimension: 3\nsizes: 5 4 3\n"
                                  "encoding: raw\nendian: little\ndata file: s%d.raw 0 2 1 2\n")
        return d / "v.nhdr"
    if kind in ("nii", "nii.gz"):
        nib.save(nib.Nifti1Image(F, np.diag([1, 2, 3, 1])), d / f"v.{kind}")
        return d / f"v.{kind}"
    if kind == "mrc":
        with mrcfile.new(d / "v.mrc") as m:
            m.set_data(F.transpose(2, 1, 0).copy())
        return d / "v.mrc"
    if kind == "slc":
        body = b"".join(b"X" + f"{5 * 4}X".encode() + F[:, :, k].astype(np.uint8).T.tobytes()
                        for k in range(3))
        (d / "v.slc").write_bytes(b"11111 5 4 3 8\n1.0 1.0 1.0\n0 0 0 0 0 0 X" + body)
        return d / "v.slc"
    raise ValueError(kind)


def _points_file(kind, d):
    import meshio
    import pyvista as pv
    from plyfile import PlyData, PlyElement

    if kind in ("ply-ascii", "ply-binary"):
        v = np.zeros(len(PTS), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
        v["x"], v["y"], v["z"] = PTS.T
        PlyData([PlyElement.describe(v, "vertex")], text=kind == "ply-ascii").write(
            str(d / "c.ply"))
        return d / "c.ply"
    if kind == "xyz":
        np.savetxt(d / "c.xyz", PTS)
        return d / "c.xyz"
    if kind == "pcd":
        body = "\n".join(" ".join(f"{c:.5f}" for c in p) for p in PTS)
        (d / "c.pcd").write_text(
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {len(PTS)}\nHEIGHT 1\nPOINTS {len(PTS)}\nDATA ascii\n{body}\n")
        return d / "c.pcd"
    mesh = pv.Icosphere(nsub=0)
    if kind == "off":
        meshio.write(d / "c.off", meshio.Mesh(mesh.points,
                                              [("triangle", mesh.faces.reshape(-1, 4)[:, 1:])]))
        return d / "c.off"
    sv.write_mesh(d / f"c.{kind}", mesh)
    return d / f"c.{kind}"


VOLUMES = ["vti", "nrrd", "npy", "vtk", "mha", "mhd", "mhd-zraw", "nhdr", "nhdr-slices", "nii",
           "nii.gz", "mrc", "slc"]
POINTS = ["ply-ascii", "ply-binary", "xyz", "pcd", "off", "obj", "stl"]
MESHES = ["ply", "obj", "stl", "vtp"]


def _make(kind, d):
    """(path of the file to mutate, function reading it and checking the result)."""
    if kind in VOLUMES:
        def read(p):
            vol = sv.read_volume(p)
            assert np.isfinite(vol.data).all() and min(vol.spacing) > 0
        return _volume_file(kind, d), read
    if kind in POINTS:
        def read(p):
            assert np.isfinite(np.asarray(sv.read_points(p).points)).all()
        return _points_file(kind, d), read
    if kind.startswith("mesh-"):
        import pyvista as pv

        path = sv.write_mesh(d / f"m.{kind[5:]}", pv.Icosphere(nsub=1))

        def read(p):
            m = sv.read_mesh(p)
            assert np.isfinite(np.asarray(m.points)).all()
        return path, read
    if kind == "png":
        path = sv.write_screenshot(d / "s.png", np.full((4, 6, 3), 200, np.uint8))
        return path, sv.io.meshes.read_image
    raise ValueError(kind)


KINDS = VOLUMES + POINTS + [f"mesh-{m}" for m in MESHES] + ["png"]

HOSTILE_NUMBERS = [b"0", b"-1", b"1", b"65536", b"4294967296", b"99999999999999999999", b"nan",
                   b"1e309", b"-1e309", b"2147483648", b"", b"0x10", b"1.5"]

byte_mutation = st.tuples(st.sampled_from(["truncate", "flip", "insert", "zero"]),
                          st.floats(0.0, 1.0), st.integers(1, 64), st.integers(0, 255))
header_edit = st.tuples(st.just("header"), st.integers(0, 10_000),
                        st.sampled_from(HOSTILE_NUMBERS))
mutation = st.one_of(byte_mutation, header_edit)

_NUMBER = re.compile(rb"(?<![A-Za-z_])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def _mutate(data: bytes, m) -> bytes:
    if m[0] == "header":
        _, which, value = m
        numbers = list(_NUMBER.finditer(data[:1024]))
        if not numbers:
            return data
        hit = numbers[which % len(numbers)]
        return data[:hit.start()] + value + data[hit.end():]
    op, where, n, byte = m
    i = int(where * len(data))
    if op == "truncate":
        return data[:i]
    if op == "flip":
        return data[:i] + bytes(b ^ (byte or 1) for b in data[i:i + n]) + data[i + n:]
    if op == "insert":
        return data[:i] + bytes([byte]) * n + data[i:]
    return data[:i] + b"\0" * n + data[i + n:]


def _read_one(read, path, tried, part):
    t = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            read(path)
        except SplinevizError as exc:
            msg = str(exc)
            assert msg and "\n" not in msg and len(msg) <= 300, msg
    # documented acceptances warn with SplinevizWarning; a library's warning must not leak
    assert all(issubclass(w.category, SplinevizWarning) for w in caught), \
        [f"{w.category.__name__}: {w.message}" for w in caught]
    assert time.perf_counter() - t < SECONDS
    tried[part] += 1


def _files_of(kind, path):
    """The header and, for detached formats, the payload files: both get mutated."""
    d = path.parent
    return [p for p in sorted(d.iterdir()) if p.is_file()] if kind in (
        "mhd", "mhd-zraw", "nhdr", "nhdr-slices") else [path]


def _fuzz_files(examples):
    @pytest.mark.parametrize("kind", KINDS)
    @settings(max_examples=examples, derandomize=True, deadline=None, database=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture,
                                     HealthCheck.too_slow])
    @given(mutations=st.lists(mutation, min_size=1, max_size=3), which=st.integers(0, 7))
    def test(kind, tmp_path_factory, tried, mutations, which):
        d = tmp_path_factory.mktemp(kind.replace(".", "_"))
        path, read = _make(kind, d)
        files = _files_of(kind, path)
        target = files[which % len(files)]
        original = target.read_bytes()
        data = original
        for m in mutations:
            data = _mutate(data, m)
        target.write_bytes(data)
        _read_one(read, path, tried, "file mutants")

    return test


test_mutated_files = _fuzz_files(30)
test_mutated_files_many = pytest.mark.slow(_fuzz_files(300))


# ---------------------------------------------------------------------------- sessions
def _session_doc():
    return {"format": "splineviz-session", "schema_version": 3, "app_version": "0.1.0",
            "objects": [
                {"id": "v", "type": "VolumeFile", "name": "vol",
                 "properties": {"path": "v.npy", "sigma": 0.5}},
                {"id": "i", "type": "Isosurface", "inputs": ["v"],
                 "properties": {"isovalue": 1.5, "model": "trilinear", "color": [1, 0, 0]}},
                {"id": "p", "type": "PointsFile", "properties": {"path": "c.xyz"}},
                {"id": "m", "type": "MeshFile", "inputs": ["p"],
                 "properties": {"path": "m.ply", "edge_length": 0.3}},
                {"id": "c", "type": "ClipPlane", "inputs": ["i"],
                 "properties": {"origin": [1, 2, 3], "normal": [0, 0, 1]}}],
            "views": [{"id": "view1", "camera": {"position": [9, 9, 9]},
                       "lights": [{"type": "scene", "position": [1, 1, 1]}]}]}


HOSTILE_VALUES = [None, True, -1, 0, 2**63, 1e308, -1e308, "", "x" * 5000, [], {}, [[[[]]]],
                  "../outside.npy", "/etc/passwd", "/dev/zero", "link.npy", "v.npy\x00.txt",
                  "C:\\\\x", "~/x", {"$ref": "#"}, [0, 0, 0], [1e16, 0, 0], "#ff0000",
                  "NaN", 1.5, "trilinear", "Isosurface", "VolumeFile", ["v", "v"]]


def _paths(node, prefix=()):
    """Every (path, value) of a JSON document, depth first."""
    yield prefix, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


def _replace(doc, path, value):
    if not path:
        return value
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return doc


session_edit = st.one_of(
    st.tuples(st.just("value"), st.integers(0, 10_000), st.sampled_from(HOSTILE_VALUES)),
    st.tuples(st.just("delete"), st.integers(0, 10_000), st.none()),
    st.tuples(st.just("version"), st.integers(-2, 5), st.none()))


def _edit_session(doc, edit):
    op, which, value = edit
    if op == "version":
        doc["schema_version"] = which
        return doc
    paths = [p for p, _ in _paths(doc)][1:]
    path = paths[which % len(paths)]
    if op == "delete":
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        del parent[path[-1]]
        return doc
    return _replace(doc, path, copy.deepcopy(value))  # never the shared constant itself


@pytest.fixture(scope="module")
def session_folder(tmp_path_factory):
    """One folder with the session's data beside it and a file outside it."""
    import os

    import pyvista as pv

    root = tmp_path_factory.mktemp("sessions")
    d = root / "project"
    d.mkdir()
    np.save(d / "v.npy", F)
    np.savetxt(d / "c.xyz", PTS)
    sv.write_mesh(d / "m.ply", pv.Icosphere(nsub=0))
    np.save(root / "outside.npy", F)
    os.symlink(root / "outside.npy", d / "link.npy")
    return d


def _fuzz_sessions(examples):
    @settings(max_examples=examples, derandomize=True, deadline=None, database=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture,
                                     HealthCheck.too_slow])
    @given(edits=st.lists(session_edit, min_size=1, max_size=4),
           text_mutation=st.one_of(st.none(), byte_mutation))
    def test(session_folder, tried, edits, text_mutation):
        from splineviz.model.session import read_session_data

        doc = _session_doc()
        for e in edits:
            doc = _edit_session(doc, e)
        text = json.dumps(doc).encode()
        if text_mutation is not None:
            text = _mutate(text, text_mutation)
        path = session_folder / "s.svs"
        path.write_bytes(text)
        t = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SplinevizWarning)  # documented acceptances
                s = load_session(path)
                # a session that loads names only files inside its folder
                for _, p in s.data_files():
                    assert p.resolve().is_relative_to(session_folder.resolve()), p
                read_session_data(s)
        except SplinevizError as exc:
            assert str(exc) and "\n" not in str(exc) and len(str(exc)) <= 300
        assert time.perf_counter() - t < SECONDS
        tried["session mutants"] += 1

    return test


test_mutated_sessions = _fuzz_sessions(800)
test_mutated_sessions_many = pytest.mark.slow(_fuzz_sessions(10000))
