"""Drives the real application in a subprocess for the kill-and-restore test, and describes a
scene for comparing it before the kill and after the restore.

``python recovery_driver.py edit OUT``: starts the app as ``splineviz`` does (no file: the
default data), edits the scene once the window is up (isovalue, model, a volume made in
Python, a clip plane, the camera), writes the scene's description to ``OUT.json`` and, once
the autosave has written the recovery file, ``OUT.saved``; then it keeps running until
killed.

``python recovery_driver.py report OUT``: starts the app (``$SPLINEVIZ_RECOVER=restore``
answers the recovery question), waits until the restored scene is in, writes its
description to ``OUT.json`` and quits cleanly.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np


def describe(scene) -> dict:
    """Everything a restore must give back: every object's properties and data (a digest
    of the samples of data without a file), the camera and the view."""
    objects = []
    for node in scene:
        entry = {"id": node.id, "kind": node.kind, "name": node.name,
                 **node.model_dump(mode="json", exclude={"id", "name", "kind"})}
        data = getattr(node, "data", None)
        if data is not None and hasattr(data, "data"):  # a volume
            arr = np.asarray(data.data, dtype=np.float64)
            entry["samples"] = [list(arr.shape), round(float(arr.sum()), 6),
                                round(float((arr * np.arange(arr.size).reshape(arr.shape))
                                            .sum()), 3)]
            entry["grid"] = [list(map(float, data.spacing)), list(map(float, data.origin))]
        objects.append(entry)
    return {"objects": objects, "camera": scene.camera.model_dump(mode="json"),
            "view": scene.view.model_dump(mode="json")}


def edit(scene) -> None:
    """The changes made before the kill: one of each kind a restore must bring back."""
    import splineviz as sv

    iso = scene.isosurfaces[0]
    iso.isovalue = 0.31
    iso.model = "trilinear"
    iso.opacity = 0.7
    x = np.linspace(-1, 1, 11)
    ball = np.add.outer(np.add.outer(x**2, x**2), x**2)
    made = scene.add_volume(sv.Volume(ball, spacing=(0.2, 0.2, 0.25), origin=(1.5, -1, -1)),
                            "made in Python", isovalue=0.5, model="trilinear")
    scene.add_clip_plane(origin=(0.1, 0.0, 0.0), normal=(0.0, 1.0, 0.0),
                         volume=scene.volumes[0])
    made.sigma = 0.0
    scene.camera.update(position=(4.0, -5.0, 3.0), focal_point=(0.5, 0.0, 0.0),
                        view_up=(0.0, 0.0, 1.0), view_angle=25.0)


def _write(path: str, text: str) -> None:
    with open(path + ".part", "w") as fh:
        fh.write(text)
    os.replace(path + ".part", path)


def main(phase: str, out: str) -> int:
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    app = QApplication(sys.argv[:1])  # run_gui takes this one

    def window():
        from splineviz.gui.main_window import MainWindow

        found = [w for w in app.topLevelWidgets() if isinstance(w, MainWindow)]
        return found[0] if found else None

    def step():
        w = window()
        if w is None or not w.isVisible() or w.busy() or w.autosaver is None:
            QTimer.singleShot(50, step)
            return
        if phase == "edit":
            edit(w.scene)
            _write(out + ".json", json.dumps(describe(w.scene)))
            w.autosaver.saved.connect(lambda _p: _write(out + ".saved", _p))
        elif not any("warning: restored" in line for line in w.log.lines()):
            QTimer.singleShot(50, step)  # the restore job has not finished yet
        else:
            _write(out + ".json", json.dumps(describe(w.scene)))
            w.ask_before_closing = False
            w.close()

    QTimer.singleShot(0, step)
    from splineviz.cli import main as cli_main

    return cli_main(["--size", "160x120"])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
