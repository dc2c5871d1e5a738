"""Ray-casting benchmark (issue 4): ``pytest tests/bench/test_bench_raycast.py -m bench -s`` or
``splineviz bench raycast``. Prints classify/frame times, active cells and ratios against VTK
flying edges + offscreen rendering and against the trilinear ray caster, all from one run."""

import pytest


@pytest.mark.bench
def test_bench_raycast(monkeypatch, shared_data):
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    from splineviz.bench.raycast import run_bench

    rows = run_bench(shared_data / "volumes", size=(512, 512), repeats=3)
    timed = [r for r in rows if "frame_s" in r]
    assert timed and all(r["frame_s"] > 0 and r["active_cells"] > 0 for r in timed)
