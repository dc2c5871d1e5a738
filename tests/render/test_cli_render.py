"""``splineviz render``: PNG output, camera/clip parsing and one-line errors."""

import numpy as np
import pytest

from splineviz.cli import main
from splineviz.cli.render import RenderArgumentError, make_camera
from splineviz.core.testfunctions import ml
from splineviz.core.volume import Volume


def _read_png(path):
    pv = pytest.importorskip("pyvista")
    img = pv.read(str(path))
    w, h, _ = img.dimensions
    arr = np.asarray(img.point_data[img.array_names[0]]).reshape(h, w, -1)
    return arr[::-1]  # VTK images start at the bottom row


def test_render_command_writes_the_frame(tmp_path, capsys):
    vol, iso = Volume.from_function(ml, (21, 21, 21), ml.domain), ml.isovalue
    np.save(tmp_path / "ml.npy", vol.data)
    out = tmp_path / "ml.png"
    rc = main(["render", str(tmp_path / "ml.npy"), "--iso", str(iso), "--model", "trilinear",
               "--size", "48x36", "--clip", "10,10,10,1,0,0", "-o", str(out)])
    assert rc == 0
    assert "48x36" in capsys.readouterr().out
    img = _read_png(out)
    assert img.shape[:2] == (36, 48)
    # the surface is visible and the background is the app's background colour
    assert len(np.unique(img.reshape(-1, img.shape[2]), axis=0)) > 10
    assert tuple(img[0, 0, :3]) == (26, 26, 36)


@pytest.mark.parametrize("args,msg", [(["--camera", "1,2"], "--camera needs"),
                                      (["--clip", "0,0,0,0,0"], "--clip needs"),
                                      (["--camera", "5,5,5,5,5,5"], "bad --camera")])
def test_render_argument_errors_are_one_line(tmp_path, capsys, args, msg):
    np.save(tmp_path / "v.npy", np.zeros((4, 4, 4)))
    rc = main(["render", str(tmp_path / "v.npy"), "--model", "trilinear", "-o",
               str(tmp_path / "x.png"), *args])
    err = capsys.readouterr().err
    assert rc == 2 and msg in err and len(err.strip().splitlines()) == 1


def test_make_camera_forms():
    b = ((0, 10), (0, 20), (0, 30))
    cam = make_camera("50,0,0", b, 30)
    assert cam.focal_point == (5.0, 10.0, 15.0)
    cam = make_camera("50,0,0,1,2,3,0,1,0", b, 25)
    assert cam.focal_point == (1.0, 2.0, 3.0) and cam.view_up == (0.0, 1.0, 0.0)
    with pytest.raises(RenderArgumentError):
        make_camera("a,b,c", b, 30)
