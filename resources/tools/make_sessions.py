"""Rebuild the example sessions of ``resources/sessions`` (run after a schema change).

Every example opens synthetic data of the first-party ``sources`` plugin (no data files) and
has a camera computed with :meth:`splineviz.model.Scene.frame` that shows the whole data box
with its axes labels. The documents are written by :func:`splineviz.model.session.to_session`
and then tidied (rounded camera, short lists on one line) for people reading them.

Usage::

    python resources/tools/make_sessions.py [--render FOLDER] [NAME ...]

``--render`` also writes a 640x480 PNG of each session (to look at before committing).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from splineviz.io.session import save_session
from splineviz.model import Scene
from splineviz.model.session import load_scene, to_session
from splineviz.plugins import source_volume

SESSIONS = Path(__file__).resolve().parents[1] / "sessions"


def look(scene: Scene, direction, up=(0.0, 0.0, 1.0), zoom=0.86, drop=0.04):
    """Camera on ``direction`` from the data, framing all of it (:meth:`Scene.frame`), then
    backed off by ``1 / zoom`` (room for the axes labels) and aimed ``drop`` box heights
    lower (the labels under the box)."""
    d = np.asarray(direction, float)
    d /= np.linalg.norm(d)
    scene.camera.update(view_angle=30.0, position=tuple(map(float, d * 10)),
                        focal_point=(0.0, 0.0, 0.0), view_up=tuple(map(float, up)))
    scene.frame()
    b = np.asarray(scene.bounds())
    cam = scene.camera
    focal = np.asarray(cam.focal_point) - np.array([0.0, 0.0, drop * (b[2, 1] - b[2, 0])])
    dist = np.linalg.norm(np.subtract(cam.position, cam.focal_point)) / zoom
    cam.update(focal_point=tuple(map(float, focal)), position=tuple(map(float, focal + d * dist)))


def source(scene: Scene, name: str, title: str, shape=None):
    return scene.add_volume(source_volume(name, shape), title, source=name, isosurface=False)


def marschner_lobb() -> Scene:
    """The embedded default data: Marschner-Lobb 41^3, cubic C1 at 0.5."""
    s = Scene()
    v = source(s, "marschner-lobb", "Marschner-Lobb 41^3")
    s.add_isosurface(v, isovalue=0.5, model="cubic-c1", name="f = 0.5")
    look(s, (1.0, -1.35, 0.85))
    return s


def two_surfaces_clipped() -> Scene:
    """Two isosurfaces of one volume (a translucent one over an opaque one) and a clip
    plane of that volume cutting the near half away (its profile shows)."""
    s = Scene()
    v = source(s, "marschner-lobb", "Marschner-Lobb 41^3")
    s.add_isosurface(v, isovalue=0.25, model="cubic-c1", name="f = 0.25 (translucent)",
                     color=(0.55, 0.72, 0.95), opacity=0.5)
    s.add_isosurface(v, isovalue=0.6, model="cubic-c1", name="f = 0.6", color=(0.93, 0.72, 0.45),
                     material="shiny")
    s.add_clip_plane(origin=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0), volume=v,
                     name="cut at y = 0")
    look(s, (1.0, -1.35, 0.85))
    return s


def models_compared() -> Scene:
    """Four spline models of the same coarse samples, one per quadrant (each volume keeps
    its quadrant through two clip planes of its own)."""
    s = Scene()
    quads = [("trilinear", "Trilinear (C0)", (-1, -1), (0.75, 0.75, 0.78)),
             ("super-quadratic", "Quadratic super spline (C0)", (1, -1), (0.55, 0.80, 0.55)),
             ("cubic-c1", "Cubic C1", (1, 1), (0.93, 0.78, 0.55)),
             ("to-quadratic", "Quadratic C1 (truncated octahedra)", (-1, 1),
              (0.60, 0.65, 0.95))]
    vols = []
    for model, label, _, color in quads:
        v = source(s, "marschner-lobb", f"ML 21^3, {label}", (21, 21, 21))
        s.add_isosurface(v, isovalue=0.5, model=model, name=label, color=color)
        vols.append(v)
    for v, (_, label, (sx, sy), _) in zip(vols, quads, strict=True):
        s.add_clip_plane(origin=(0.0, 0.0, 0.0), normal=(float(sx), 0.0, 0.0), volume=v,
                         name=f"{label}: x {'>' if sx > 0 else '<'} 0", show_widget=False)
        s.add_clip_plane(origin=(0.0, 0.0, 0.0), normal=(0.0, float(sy), 0.0), volume=v,
                         name=f"{label}: y {'>' if sy > 0 else '<'} 0", show_widget=False)
    look(s, (0.55, -0.75, 1.3), drop=0.0)
    return s


def barth_sextic() -> Scene:
    """Barth's sextic (thesis Fig. 5.7), cubic C1, shiny."""
    s = Scene()
    v = source(s, "barth", "Barth's sextic 64^3")
    s.add_isosurface(v, isovalue=0.0, model="cubic-c1", name="f = 0", material="shiny")
    look(s, (1.0, -1.3, 0.8))
    return s


def chmutov() -> Scene:
    """A Chmutov-type surface (thesis Fig. 6.20) with the truncated-octahedral C1 spline."""
    s = Scene()
    v = source(s, "chmutov", "Chmutov surface 64^3")
    s.add_isosurface(v, isovalue=-2.0, model="to-quadratic", name="f = -2")
    look(s, (1.0, -1.3, 0.8))
    return s


EXAMPLES = {"marschner-lobb": marschner_lobb, "two-surfaces-clipped": two_surfaces_clipped,
            "models-compared": models_compared, "barth-sextic": barth_sextic,
            "chmutov": chmutov}


def _round(value, digits=6):
    if isinstance(value, float):
        return round(value, digits) + 0.0
    if isinstance(value, list):
        return [_round(v, digits) for v in value]
    if isinstance(value, dict):
        return {k: _round(v, digits) for k, v in value.items()}
    return value


def tidy(text: str) -> str:
    """JSON with lists of numbers on one line and floats rounded."""
    doc = _round(json.loads(text))

    def dump(v, indent=0):
        pad = "  " * indent
        if isinstance(v, dict):
            items = [f'{pad}  {json.dumps(k)}: {dump(x, indent + 1)}' for k, x in v.items()]
            return "{\n" + ",\n".join(items) + f"\n{pad}}}" if items else "{}"
        if isinstance(v, list) and all(not isinstance(x, dict | list) for x in v):
            return json.dumps(v)
        if isinstance(v, list):
            return "[\n" + ",\n".join(f"{pad}  {dump(x, indent + 1)}" for x in v) + f"\n{pad}]"
        return json.dumps(v, ensure_ascii=False)

    return dump(doc) + "\n"


def write(name: str) -> Path:
    path = SESSIONS / f"{name}.svs"
    save_session(to_session(EXAMPLES[name]()), path)
    path.write_text(tidy(path.read_text(encoding="utf-8")), encoding="utf-8")
    return path


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", choices=[[], *EXAMPLES], default=[])
    ap.add_argument("--render", type=Path, help="write a 640x480 PNG of each into this folder")
    args = ap.parse_args(argv)
    SESSIONS.mkdir(exist_ok=True)
    for name in args.names or EXAMPLES:
        path = write(name)
        print(path)
        if args.render:
            from splineviz.render.scene_view import render_scene

            args.render.mkdir(parents=True, exist_ok=True)
            render_scene(load_scene(path), (640, 480), args.render / f"{name}.png")


if __name__ == "__main__":
    main()
