"""Frames and sessions recorded before the architecture refactor (issue 24) stay the same:
every model's frame on the shared data bit for bit on the OpenCL device it was recorded on (a
few sums within rounding on another; the NumPy renderer's hits and colours on any processor),
and every schema-4 session loads and saves byte for byte."""

from __future__ import annotations

import json
import shutil

import pytest

from splineviz.model.session import load_scene, save_scene

from .golden import frames as golden_frames
from .golden import sessions as golden_sessions
from .helpers import DATA

RECORDED = json.loads(golden_frames.RECORD.read_text())


@pytest.mark.skipif(not (DATA / "tooth.nrrd").exists(), reason="shared data not mounted")
@pytest.mark.parametrize("case", golden_frames.CASES, ids=[c[0] for c in golden_frames.CASES])
def test_frames_are_those_recorded(case):
    rc, frame = golden_frames.render_case(case)
    now = golden_frames.digest(frame)
    recorded = RECORDED[case[0]]
    device = rc.stats["device"]
    if device in recorded and device != "numpy":
        assert now["sha256"] == recorded[device]["sha256"], (case[0], device)
        return
    if device == "numpy":
        # NumPy and its BLAS pick their vector kernels by the processor at run time, so the
        # reference renderer's last bits are the processor's: the same hits and colours, the
        # depths within rounding (a processor with other vector units changed the bytes of
        # the tricubic blob's frame, and no hit, colour or depth sum)
        ref = recorded["numpy"]
        assert (now["hits"], now["color_sum"]) == (ref["hits"], ref["color_sum"]), case[0]
        assert now["depth_sum"] == pytest.approx(ref["depth_sum"], rel=1e-9)
        return
    # another processor's OpenCL compiler: the same picture within rounding
    ref = next(iter(recorded.values()))
    assert abs(now["hits"] - ref["hits"]) <= max(3, 0.002 * ref["hits"])
    assert now["depth_sum"] == pytest.approx(ref["depth_sum"], rel=2e-3)


@pytest.mark.parametrize("name", sorted(p.name for p in golden_sessions.FOLDER.glob("*.svs")))
def test_schema_4_sessions_load_and_save_byte_identically(name, tmp_path):
    golden_sessions.write_data(tmp_path)
    src = tmp_path / name
    shutil.copyfile(golden_sessions.FOLDER / name, src)
    out = save_scene(load_scene(src), tmp_path / f"again-{name}")
    assert out.read_bytes() == src.read_bytes()
