"""``splineviz bench`` dispatches to the benchmarks of :mod:`splineviz.bench`; the GUI table."""

from splineviz.cli import _build_parser


def test_bench_parser_knows_both_benchmarks():
    parser = _build_parser()
    a = parser.parse_args(["bench", "remesh", "--clouds", "kitten", "--timeout", "30"])
    assert (a.which, a.clouds, a.timeout) == ("remesh", "kitten", 30.0)
    b = parser.parse_args(["bench", "raycast", "--size", "64x48"])
    assert (b.which, b.size) == ("raycast", "64x48")
    assert a.func is b.func


def test_bench_parser_knows_the_bricks_benchmark():
    a = _build_parser().parse_args(["bench", "bricks", "--n", "256", "--brick", "64",
                                    "--workers", "1,2", "--size", "320x240"])
    assert (a.which, a.n, a.brick, a.workers) == ("bricks", 256, 64, "1,2")



def test_bench_parser_knows_the_gui_benchmark():
    a = _build_parser().parse_args(["bench", "gui", "--repeats", "5", "--volume", "bonsai.vti",
                                    "--iso", "40.5", "--clouds", "bunny.ply"])
    assert (a.which, a.repeats, a.volume, a.iso, a.clouds) == ("gui", 5, "bonsai.vti", 40.5,
                                                               "bunny.ply")


def test_bench_gui_without_a_display_is_one_line(monkeypatch, capsys):
    from splineviz.cli import main

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["bench", "gui"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("splineviz: error: bench gui") and "xvfb-run" in err
    assert "\n" not in err


def test_gui_table_medians_against_the_budget():
    from splineviz.bench.gui import MAX_STALL_MS, Stalls, print_table

    stalls = Stalls(ms={"orbit": [30.0, 250.0, 40.0], "wheel": [120.0, 90.0, 130.0]},
                    settled_s={"orbit": [1.0, 3.0, 2.0]}, cancel_s=[0.2, 0.1, 0.3])
    lines = []
    rows = print_table(stalls, out=lines.append)
    orbit, wheel = rows
    assert (orbit["median_ms"], orbit["max_ms"], orbit["ok"]) == (40.0, 250.0, True)
    assert (wheel["median_ms"], wheel["ok"], wheel["budget_ms"]) == (120.0, False, MAX_STALL_MS)
    assert orbit["median_ms"] <= orbit["p95_ms"] <= orbit["max_ms"]
    assert (orbit["settled_s"], wheel["settled_s"]) == (2.0, None)
    assert any(line.startswith("| wheel") and "| NO  |" in line for line in lines)
    assert any(line.startswith("| orbit") and line.rstrip().endswith("| yes |      2.00 |")
               for line in lines)
    assert lines[-1].startswith("cancel: the job stopped after 0.20 s (median of 3, max 0.30 s")


def test_python_dash_m_splineviz_is_the_command():
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "splineviz", "--version"], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.startswith("splineviz ")


def test_bench_parser_knows_the_movie_benchmark():
    a = _build_parser().parse_args(["bench", "movie", "--sizes", "720p,4K", "--frames", "3"])
    assert (a.which, a.sizes, a.frames) == ("movie", "720p,4K", 3)


def test_bench_parser_knows_the_cad_scans_benchmark():
    a = _build_parser().parse_args(["bench", "cad-scans", "--shapes", "bracket", "--noises",
                                    "0,0.005", "--points", "20000", "--out", "pics"])
    assert (a.which, a.shapes, a.noises, a.points, a.out) == ("cad-scans", "bracket", "0,0.005",
                                                              20000, "pics")


def test_bench_cad_scans_refuses_an_unknown_shape_in_one_sentence():
    import pytest

    from splineviz.core.errors import SplinevizError

    a = _build_parser().parse_args(["bench", "cad-scans", "--shapes", "teapot"])
    with pytest.raises(SplinevizError, match="unknown cad-scans shape 'teapot'"):
        a.func(a)
    b = _build_parser().parse_args(["bench", "cad-scans", "--noises", "low"])
    with pytest.raises(SplinevizError, match="--noises takes"):
        b.func(b)
