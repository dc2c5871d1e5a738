"""Spline isosurface meshes (Export mesh) and the command line that opens the app."""

import numpy as np

import splineviz as sv
from splineviz.cli import main
from splineviz.model.opening import default_volume
from splineviz.render.extract import spline_isosurface


def test_default_isosurface_lies_on_the_spline_surface():
    vol, iso = default_volume()
    s = sv.build_spline(vol, model="to-quadratic")
    mesh = spline_isosurface(s, iso)
    assert mesh.n_points > 10000
    pts = np.asarray(mesh.points)
    assert np.abs(s.evaluate(pts) - iso).max() < 1e-6
    # normals are unit and point to lower values (VTK's contour convention)
    n = mesh.point_data.active_normals
    assert np.allclose(np.linalg.norm(n, axis=1), 1)
    g = s.gradient(pts[:100])
    assert np.all(np.einsum("nc,nc->n", g, n[:100]) < 0)


def test_missing_file_is_one_line_error(capsys):
    assert main(["/nonexistent/volume.vti"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("splineviz: error:")
