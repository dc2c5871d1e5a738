"""Time-series benchmark (issue 27): ``pytest tests/bench/test_bench_time_small.py -m bench
-s`` runs it small (32^3 and 48^3 steps, two models, 128x128 frames); ``splineviz bench
time`` runs the full table (256^3 and 128^3, 20 steps, all models, 512x512 frames)."""

import numpy as np
import pytest


def test_series_is_written_and_read_back(tmp_path):
    from splineviz.bench.time import make_series
    from splineviz.io.time_series import open_time_series

    series = open_time_series(make_series(tmp_path, 16, 3))
    assert len(series) == 3 and series.step(2).shape == (16, 16, 16)
    a, b = (np.asarray(series.step(k).data, dtype=int) for k in (0, 2))
    assert a.dtype == b.dtype and 0 < (a > 128).mean() < 1 and np.any(a != b)


@pytest.mark.bench
def test_bench_time(monkeypatch):
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    from splineviz.bench.time import run_time_bench

    lines = []
    rows = run_time_bench(n=48, steps=6, preview_n=32, models=("trilinear", "cubic-c1"),
                          size=(128, 128), preview=(64, 64), timeout=300, out=lines.append)
    print("\n".join(lines))
    assert len(rows) == 4 and all("error" not in r for r in rows), rows
    for r in rows:
        assert r["change_s"] > 0 and r["rate"] > 0 and r["rss"] > 0
    assert all(f"{r['vs_vtk']:.2f}" in "\n".join(lines) for r in rows if r["n"] == 48)
    spline = [ln for ln in lines if ln.strip().startswith(("cubic-c1", "to-quadratic"))]
    assert len(spline) == 2
