"""The axes grid of a view (issue 26, part 6): round tick labels of the data shown,
refreshed for each data set and in each view of a split."""

import numpy as np
import pyvista as pv

import splineviz as sv
from splineviz.model import Scene
from splineviz.render.scene_view import SceneView


def _labels(grid, axis):
    arr = grid.GetAxisLabels(axis)
    return [arr.GetValue(i) for i in range(arr.GetNumberOfValues())]


def _titles(grid):
    return grid.GetXTitle(), grid.GetYTitle(), grid.GetZTitle()


def test_labels_and_titles_follow_each_data_set_in_each_view():
    scene = Scene()
    scene.add_volume(sv.Volume(np.zeros((4, 4, 4)), spacing=(10 / 3, 1, 1),
                               origin=(6e-29, -1.5, 0.0)), "first", isosurface=False)
    views = []
    for side in ("left", "right"):
        # big enough for every label (a narrow view thins them: test_drive_findings)
        pl = pv.Plotter(off_screen=True, window_size=(800, 600))
        views.append((pl, SceneView(scene, pl, side=side)))
    scene.view.split = True
    try:
        for _pl, view in views:
            grid = view._grid
            assert _titles(grid) == ("X", "Y", "Z")
            assert _labels(grid, 0) == ["0", "2", "4", "6", "8", "10"]
            # seven ticks: every other one labelled, 0 among them
            assert _labels(grid, 1) == ["", "-1.0", "", "0", "", "1.0", ""]
        scene.clear()
        scene.add_volume(sv.Volume(np.zeros((4, 4, 4)), spacing=0.05,
                                   origin=(-0.094, 0.0, 0.0)), "bunny", isosurface=False)
        for pl, view in views:
            grid = view._grid
            assert _titles(grid) == ("X (x 1e-3)", "Y (x 1e-3)", "Z (x 1e-3)")
            xs = _labels(grid, 0)
            assert xs[1] == "-80" and "0" in xs and "-0" not in xs  # ticks -100..60 mm
            pl.render()  # the actor draws these labels (no VTK error on the count)
    finally:
        for pl, view in views:
            view.close()
            pl.close()
