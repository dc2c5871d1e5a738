"""Mutation fuzzing of every reader: truncations, byte flips and insertions of valid files
must either read or raise a SplinevizError — never another exception, never a crash.

Hypothesis runs derandomized (reproducible) with few examples per format by default; the
``slow`` variant runs many more.
"""

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import splineviz as sv
from splineviz.core.errors import SplinevizError
from splineviz.io.session import load_session

FIELD = (np.arange(5 * 4 * 3, dtype=np.float32).reshape(5, 4, 3) % 7) - 2.5
PTS = np.random.default_rng(3).normal(size=(12, 3))


def _make(kind, d):
    """Write one valid file of ``kind`` into ``d`` and return (path, reader)."""
    import meshio
    import mrcfile
    import nibabel as nib
    import pyvista as pv
    from plyfile import PlyData, PlyElement

    vol = sv.Volume(FIELD, spacing=(1, 2, 3), origin=(4, 5, 6))
    if kind in ("vti", "nrrd", "npy"):
        sv.write_volume(d / f"v.{kind}", vol)
        return d / f"v.{kind}", sv.read_volume
    if kind == "vtk":
        img = pv.ImageData(dimensions=FIELD.shape)
        img.point_data["s"] = FIELD.ravel(order="F")
        img.save(d / "v.vtk")
        return d / "v.vtk", sv.read_volume
    if kind == "mha":
        (d / "v.mha").write_bytes(
            b"ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementType = MET_FLOAT\n"
            b"ElementDataFile = LOCAL\n" + FIELD.astype("<f4").ravel(order="F").tobytes())
        return d / "v.mha", sv.read_volume
    if kind == "nii":
        nib.save(nib.Nifti1Image(FIELD, np.eye(4)), d / "v.nii")
        return d / "v.nii", sv.read_volume
    if kind == "mrc":
        with mrcfile.new(d / "v.mrc") as m:
            m.set_data(FIELD.transpose(2, 1, 0).copy())
        return d / "v.mrc", sv.read_volume
    if kind in ("ply-ascii", "ply-binary"):
        v = np.zeros(len(PTS), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
        v["x"], v["y"], v["z"] = PTS.T
        PlyData([PlyElement.describe(v, "vertex")], text=kind == "ply-ascii").write(
            str(d / "c.ply"))
        return d / "c.ply", sv.read_points
    if kind == "xyz":
        np.savetxt(d / "c.xyz", PTS)
        return d / "c.xyz", sv.read_points
    if kind == "pcd":
        body = "\n".join(" ".join(f"{c:.5f}" for c in p) for p in PTS)
        (d / "c.pcd").write_text(
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {len(PTS)}\nHEIGHT 1\nPOINTS {len(PTS)}\nDATA ascii\n{body}\n")
        return d / "c.pcd", sv.read_points
    if kind in ("off", "obj", "stl"):
        mesh = pv.Icosphere(nsub=0)
        if kind == "off":
            meshio.write(d / "c.off", meshio.Mesh(mesh.points,
                                                  [("triangle", mesh.faces.reshape(-1, 4)[:, 1:])]))
        else:
            sv.write_mesh(d / f"c.{kind}", mesh)
        return d / f"c.{kind}", sv.read_points
    if kind == "svs":
        np.save(d / "v.npy", FIELD)
        doc = {"format": "splineviz-session", "schema_version": 2,
               "objects": [{"id": "v", "type": "VolumeFile", "properties": {"path": "v.npy"}},
                           {"id": "i", "type": "Isosurface", "inputs": ["v"],
                            "properties": {"isovalue": 1.5, "color": [1, 0, 0]}},
                           {"id": "c", "type": "ClipPlane", "inputs": ["i"],
                            "properties": {"origin": [1, 2, 3], "normal": [0, 0, 1]}}],
               "views": [{"id": "view1", "camera": {"position": [9, 9, 9]}}]}
        (d / "s.svs").write_text(json.dumps(doc))
        return d / "s.svs", load_session
    raise ValueError(kind)


KINDS = ["vti", "nrrd", "npy", "vtk", "mha", "nii", "mrc", "ply-ascii", "ply-binary", "xyz",
         "pcd", "off", "obj", "stl", "svs"]

mutation = st.tuples(
    st.sampled_from(["truncate", "flip", "insert", "zero"]),
    st.floats(0.0, 1.0), st.integers(1, 64), st.integers(0, 255))


def _mutate(data: bytes, m) -> bytes:
    op, where, n, byte = m
    i = int(where * len(data))
    if op == "truncate":
        return data[:i]
    if op == "flip":
        return data[:i] + bytes(b ^ (byte or 1) for b in data[i:i + n]) + data[i + n:]
    if op == "insert":
        return data[:i] + bytes([byte]) * n + data[i:]
    return data[:i] + b"\0" * n + data[i + n:]


def _check(kind, tmp_path_factory, mutations):
    d = tmp_path_factory.mktemp(kind)
    path, reader = _make(kind, d)
    original = path.read_bytes()
    for m in mutations:
        path.write_bytes(_mutate(original, m))
        try:
            reader(path)
        except SplinevizError as exc:
            assert "\n" not in str(exc)


def _fuzz(examples):
    @pytest.mark.parametrize("kind", KINDS)
    @settings(max_examples=examples, derandomize=True, deadline=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture,
                                     HealthCheck.too_slow])
    @given(mutations=st.lists(mutation, min_size=1, max_size=3))
    def test(kind, tmp_path_factory, mutations):
        _check(kind, tmp_path_factory, mutations)

    return test


test_mutated_files_read_or_raise_splineviz_errors = _fuzz(12)
test_mutated_files_many = pytest.mark.slow(_fuzz(300))
