"""``splineviz bench`` dispatches to the ray-casting and remeshing benchmarks."""

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

