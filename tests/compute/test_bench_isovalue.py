"""``splineviz bench isovalue``: the command line and the table (the benchmark itself runs with
``-m bench``, see tests/bench/test_bench_isovalue_small.py)."""

import numpy as np

from splineviz.bench.isovalue import _print_table, _rotated
from splineviz.cli import _build_parser
from splineviz.core.camera import Camera


def test_parser_selects_sizes_and_models():
    a = _build_parser().parse_args(["bench", "isovalue", "--sizes", "256", "--models",
                                    "trilinear,cubic-c1", "--preview", "64x48"])
    assert (a.which, a.sizes, a.models, a.preview) == ("isovalue", "256",
                                                       "trilinear,cubic-c1", "64x48")


def test_rotated_camera_keeps_distance_and_turns_about_up():
    cam = Camera((10.0, 0.0, 3.0), (0.0, 0.0, 1.0), view_up=(0, 0, 1))
    r = _rotated(cam, 90.0)
    np.testing.assert_allclose(r.position, (0.0, 10.0, 3.0), atol=1e-12)
    np.testing.assert_allclose(r.focal_point, cam.focal_point)


def test_table_prints_ratios_and_errors():
    vtk = {"extract_s": 0.2, "first_s": 1.0, "move_s": 0.5, "triangles": 1000, "rss": 2**30}
    ok = {"n": 256, "model": "cubic-c1", "volume_bytes": 2**26, "vtk": vtk, "change_s": 1e-4,
          "first_s": 0.6, "preview_s": 0.05, "move_s": 0.25, "rss": 2**29,
          "change_vs_fe": 5e-4, "first_vs_fe_first": 0.5, "move_vs_vtk": 0.5,
          "rss_vs_vtk": 0.5}
    bad = {"n": 256, "model": "to-quadratic", "volume_bytes": 2**26, "vtk": vtk,
           "error": "timed out after 600 s"}
    lines = []
    _print_table([ok, bad], (512, 512), (128, 128), lines.append)
    assert "1.200" in lines[2] and "1000 triangles" in lines[2]  # FE + first render
    assert lines[3].split()[:4] == ["256", "cubic-c1", "0.00010", "0.001"]
    assert "0.500" in lines[3] and lines[3].split()[-1] == "8.0"  # RSS / volume
    assert lines[4].endswith("timed out after 600 s")


def test_one_measurement_runs_end_to_end(tmp_path):
    """The measuring functions themselves (in this process, on a tiny volume): a broken
    import or call inside them would otherwise only show as an error row of the table."""
    from splineviz.bench.isovalue import _measure_caster, _measure_vtk

    x = np.linspace(0, 255, 12)
    data = np.add.outer(np.add.outer(x, x), x).astype(np.float32) / 3
    np.save(tmp_path / "v.npy", data)
    row = _measure_caster(tmp_path / "v.npy", (1.0, 1.0, 1.0), "trilinear", (32, 24), (16, 12),
                          None)
    assert row["change_s"] >= 0 and row["first_s"] > 0
    vtk = _measure_vtk(tmp_path / "v.npy", (1.0, 1.0, 1.0), (32, 24))
    assert vtk["triangles"] > 0
