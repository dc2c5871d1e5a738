"""Session documents of schema 4 recorded before the architecture refactor of issue 24:
every session shipped in ``resources/sessions`` as the app saves it, and one scene that sets
every property of every node type to a value other than its default.

``python -m tests.compute.golden.sessions --record`` rewrites ``sessions/``; the test loads each
document and saves it again, byte for byte.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
FOLDER = HERE / "sessions"
RESOURCES = HERE.parents[2] / "resources" / "sessions"


def write_data(folder: Path) -> None:
    """The data files the comprehensive session reads (deterministic, tiny)."""
    from splineviz.io.meshes import write_mesh

    x = np.linspace(-1.0, 1.0, 9)
    field = np.add.outer(np.add.outer(x ** 2, 0.8 * x ** 2), 1.2 * x ** 2).astype(np.float32)
    np.save(folder / "ball.npy", field)
    rng = np.random.default_rng(7)
    pts = rng.normal(size=(40, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    write_mesh(folder / "cloud.ply", (pts, np.zeros((0, 3), dtype=np.int64)))
    tet_v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    tet_f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    write_mesh(folder / "tet.ply", (tet_v, tet_f))


def comprehensive_scene(folder: Path):
    """A scene with every node type, each property away from its default."""
    import splineviz as sv
    from splineviz.io.meshes import read_mesh
    from splineviz.io.points import read_points
    from splineviz.io.volumes import read_volume
    from splineviz.model.nodes import mesh_arrays
    from splineviz.model.scene import Scene
    from splineviz.plugins import source_volume

    write_data(folder)
    scene = Scene()
    opts = {"spacing": [0.5, 0.25, 0.75], "origin": [1.0, -2.0, 3.0]}
    vol = scene.add_volume(read_volume(folder / "ball.npy", **opts), "ball",
                           path=folder / "ball.npy", read_options=opts, isosurface=False)
    vol.sigma = 1.5
    vol.show_outline = False
    ml = scene.add_volume(source_volume("marschner-lobb", (17, 17, 17)), "ML",
                          source="marschner-lobb", isosurface=False)
    ml.visible = False
    a = scene.add_isosurface(vol, 1.0, "to-quadratic", k=3, color=(0.1, 0.2, 0.3),
                             opacity=0.6, material="shiny", color_by="mean",
                             color_map="coolwarm", color_range="manual", color_min=-2.0,
                             color_max=3.5, shown_in="right", name="a")
    b = scene.add_isosurface(vol, 0.5, "trilinear", color_by="volume", color_volume_id=ml.id,
                             color_range="symmetric", material="metal", name="b")
    c = scene.add_isosurface(ml, 0.25, "super-quadratic", color_by="distance",
                             color_isosurface_id=a.id, shown_in="left", material="matte")
    c.visible = False
    scene.add_points(read_points(folder / "cloud.ply"), "cloud", path=folder / "cloud.ply",
                     color=(0.2, 0.9, 0.1), point_size=5.5, opacity=0.7, shown_in="left")
    v, f = mesh_arrays(read_mesh(folder / "tet.ply"))
    mesh = scene.add_mesh(v, f, "tet", path=str(folder / "tet.ply"), edge_length=0.25,
                          rho=0.5, color=(0.3, 0.3, 0.9), opacity=0.8, show_edges=False,
                          shown_in="right")
    mesh.visible = False
    plane = scene.add_clip_plane((1.5, -1.0, 4.0), (0.0, 1.0, 1.0), volume=vol, enabled=False,
                                 show_widget=False, name="cut")
    scene.add_clip_plane((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    scene.add_section(a, plane=plane, color=(1.0, 1.0, 0.0), line_width=5.0)
    scene.add_section(a, other=b, visible=False)
    cam = scene.camera
    cam.update(position=(10.0, -20.0, 5.0), focal_point=(1.0, 2.0, 3.0), view_up=(0, 0, 1),
               view_angle=40.0, parallel_projection=True, parallel_scale=7.5)
    scene.view.update(background=(0.2, 0.3, 0.4), show_axes=False, show_scale=False,
                      split=True)
    assert sv is not None
    return scene


def record() -> None:
    import tempfile

    from splineviz.model.session import load_scene, save_scene

    FOLDER.mkdir(exist_ok=True)
    for path in sorted(RESOURCES.glob("*.svs")):
        with tempfile.TemporaryDirectory() as tmp:
            out = save_scene(load_scene(path), Path(tmp) / path.name)
            (FOLDER / path.name).write_bytes(out.read_bytes())
    with tempfile.TemporaryDirectory() as tmp:
        out = save_scene(comprehensive_scene(Path(tmp)), Path(tmp) / "everything.svs")
        (FOLDER / "everything.svs").write_bytes(out.read_bytes())
    for p in sorted(FOLDER.glob("*.svs")):
        print(p.name, len(p.read_bytes()))


if __name__ == "__main__":
    if "--record" in sys.argv:
        record()
