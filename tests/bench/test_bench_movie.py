"""Movie benchmark (issue 28): ``pytest tests/bench/test_bench_movie.py -m bench -s`` or
``splineviz bench movie``. Prints per-frame seconds of one still, the renderer, the encoder
and the export (encoding beside rendering) at 720p, 1080p and 4K."""

import pytest


@pytest.mark.bench
def test_bench_movie(monkeypatch, shared_data):
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    from splineviz.bench.movie import SIZES, run_movie_bench

    rows = run_movie_bench(shared_data / "volumes", sizes=SIZES, frames=3)
    assert [r["label"] for r in rows] == ["720p", "1080p", "4K"]
    assert all(r["render_s"] > 0 and r["encode_s"] > 0 and r["export_s"] > 0 for r in rows)
