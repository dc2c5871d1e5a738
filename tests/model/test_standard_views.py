"""The standard views follow ParaView's convention: "+X" looks along +X (issue 26, part 6)."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.model import Scene


@pytest.mark.parametrize(("name", "look", "up"), [
    ("+X", (1, 0, 0), (0, 0, 1)), ("-X", (-1, 0, 0), (0, 0, 1)),
    ("+Y", (0, 1, 0), (0, 0, 1)), ("-Y", (0, -1, 0), (0, 0, 1)),
    ("+Z", (0, 0, 1), (0, 1, 0)), ("-Z", (0, 0, -1), (0, 1, 0))])
def test_look_down_an_axis_looks_along_it(name, look, up):
    scene = Scene()
    scene.add_volume(sv.Volume(np.zeros((4, 5, 6))), "v", isosurface=False)
    scene.frame(view=name)
    cam = scene.camera
    forward = np.subtract(cam.focal_point, cam.position)
    np.testing.assert_allclose(forward / np.linalg.norm(forward), look, atol=1e-12)
    np.testing.assert_allclose(cam.view_up, up, atol=1e-12)
