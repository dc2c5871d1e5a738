"""Isovalue-change benchmark (issue 12): ``pytest tests/bench/test_bench_isovalue_small.py
-m bench -s`` runs it small (bonsai 256^3, two models, 256x256 frames); ``splineviz bench
isovalue`` runs the full table (bonsai 256^3 and a 512^3 resample, all models, 512x512
frames)."""

import pytest


@pytest.mark.bench
def test_bench_isovalue(monkeypatch, shared_data):
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    from splineviz.bench.isovalue import run_isovalue_bench

    lines = []
    rows = run_isovalue_bench(shared_data / "volumes", sizes=(256,),
                              models=("trilinear", "cubic-c1"), size=(256, 256),
                              preview=(64, 64), timeout=300, out=lines.append)
    print("\n".join(lines))
    assert len(rows) == 2 and all("error" not in r for r in rows), rows
    for r in rows:
        assert r["vtk"]["triangles"] > 10000
        assert 0 < r["change_s"] < r["first_s"] and r["preview_s"] > 0 and r["move_s"] > 0
        assert r["rss"] > r["volume_bytes"]  # the volume is part of the peak
        # every measured ratio is in the table
        assert f"{r['change_vs_fe']:.3f}" in lines[2 + rows.index(r) + 1]
