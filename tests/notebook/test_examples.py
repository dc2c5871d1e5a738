"""The notebooks in ``examples/`` run (nbclient, a fresh kernel, no display) and every picture
they show is the exact :func:`splineviz.render.scene_view.render_scene` of its scene.

After each cell that shows a picture, the test runs a check in the same kernel: the cell's
result (``Out[n]``: a ``Scene``, the ``Picture`` of ``scene.show``, or a volume, point cloud
or mesh, whose picture is that of a new scene holding it, framed isometric) is rendered again
with ``render_scene`` directly and saved; the PNG in the cell's output must decode to the same
pixels. A picture shown any other way (``display_data``) fails the test: it would go
unchecked.
"""

import base64
import io
from pathlib import Path

import numpy as np
import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "examples").glob("*.ipynb"))
#: notebooks that read the shared data sets (skipped where they are missing)
ON_SHARED_DATA = {"point_cloud_to_mesh"}

CHECK = """
import numpy as _np
from splineviz.model import Scene as _Scene
from splineviz.notebook import DEFAULT_SIZE as _SIZE, Picture as _Picture, as_scene as _as_scene
from splineviz.render.scene_view import render_scene as _render_scene
_shown = Out[{count}]
if isinstance(_shown, _Scene):
    _ref = _render_scene(_shown, _SIZE)
elif not isinstance(_shown, _Picture):
    _own = _as_scene(_shown)
    _own.aspect = _SIZE[0] / _SIZE[1]
    _own.frame(view="isometric")
    _ref = _render_scene(_own, _SIZE)
else:
    assert isinstance(_shown, _Picture), type(_shown)
    _saved = _shown.scene.camera.pose()
    _shown.scene.camera.update(_shown.camera)
    _ref = _render_scene(_shown.scene, _shown.size)
    _shown.scene.camera.update(_saved)
_np.save({path!r}, _ref)
"""


def test_examples_exist():
    names = {p.name for p in NOTEBOOKS}
    assert {"quick_start.ipynb", "clip_and_colour.ipynb", "compare_models.ipynb",
            "point_cloud_to_mesh.ipynb"} <= names


def _png_array(data: str) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(base64.b64decode(data))))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs_and_shows_exact_pictures(path, tmp_path, monkeypatch, request):
    monkeypatch.delenv("DISPLAY", raising=False)  # as on a server: no X
    if path.stem in ON_SHARED_DATA:
        # the kernel inherits the environment: the notebook finds the data there
        monkeypatch.setenv("SPLINEVIZ_SHARED_DATA", str(request.getfixturevalue("shared_data")))
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(ROOT)}})
    checked = 0
    with client.setup_kernel():
        for index, cell in enumerate(list(nb.cells)):
            if cell.cell_type != "code":
                continue
            client.execute_cell(cell, index)
            for out in cell.outputs:
                assert out.output_type != "error", out
                assert not (out.output_type == "stream" and out.name == "stderr"), out.text
                if "image/png" not in out.get("data", {}):
                    continue
                assert out.output_type == "execute_result", "a picture shown unchecked"
                ref_path = tmp_path / f"ref{index}.npy"
                check = nbformat.v4.new_code_cell(
                    CHECK.format(count=out.execution_count, path=str(ref_path)))
                # nbclient stores a cell's outputs back into the notebook by its index
                nb.cells.append(check)
                client.execute_cell(check, len(nb.cells) - 1)
                nb.cells.pop()
                assert not [o for o in check.outputs if o.output_type == "error"], check.outputs
                shown = _png_array(out.data["image/png"])
                ref = np.load(ref_path)
                assert shown.shape == ref.shape
                assert np.array_equal(shown, ref)
                # a real picture, not the background alone
                assert len(np.unique(shown.reshape(-1, shown.shape[-1]), axis=0)) > 50
                checked += 1
    assert checked >= 1
