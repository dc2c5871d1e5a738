"""The analysis panel's Minimum/Maximum show the colour range in use, and a manual range
belongs to its measure (issue 26, part 4); through a real off-screen view of the scene."""

import pytest

pytest.importorskip("pytestqt")
pv = pytest.importorskip("pyvista")

import splineviz as sv  # noqa: E402
from splineviz.core.testfunctions import ml  # noqa: E402
from splineviz.gui.panels import AnalysisPanel  # noqa: E402
from splineviz.model import Scene  # noqa: E402
from splineviz.render.scene_view import SceneView, colour_range_link  # noqa: E402


def test_fields_show_the_range_in_use_and_manual_ranges_stay_with_their_measure(qtbot):
    scene = Scene()
    vol = scene.add_volume(sv.Volume.from_function(ml, (17, 17, 17), ml.domain), "ML",
                           isovalue=0.5, model="trilinear")
    iso = scene.isosurfaces_of(vol)[0]
    scene.frame(view="isometric")
    panel = AnalysisPanel(scene)
    qtbot.addWidget(panel)
    scene.select(iso)
    pl = pv.Plotter(off_screen=True, window_size=(160, 120))
    view = SceneView(scene, pl)
    try:
        def in_use():
            view.render_exact()
            return view.spline_scene.color_range(view.layers[iso.id])

        panel.field.setCurrentIndex(panel.field.findData("mean"))
        lo, hi = in_use()
        assert (panel.vmin.value(), panel.vmax.value()) == pytest.approx((lo, hi), abs=1e-6)
        assert not panel.vmin.isEnabled()  # shown, not set
        # manual starts from the range on screen; then the user's own numbers
        panel.range_mode.setCurrentText("manual")
        assert (iso.color_min, iso.color_max) == pytest.approx((lo, hi), abs=1e-6)
        panel.vmax.setValue(9.0)
        panel.vmin.setValue(-9.0)
        assert (iso.color_range, iso.color_min, iso.color_max) == ("manual", -9.0, 9.0)
        assert in_use() == (-9.0, 9.0)
        # another measure does not inherit it: automatic, its own range in the fields
        panel.field.setCurrentIndex(panel.field.findData("gradient-magnitude"))
        assert iso.color_range == "auto"
        lo2, hi2 = in_use()
        assert lo2 >= 0.0 and (lo2, hi2) != (-9.0, 9.0)
        assert (panel.vmin.value(), panel.vmax.value()) == pytest.approx((lo2, hi2), abs=1e-6)
        # and coming back brings the manual range back
        panel.field.setCurrentIndex(panel.field.findData("mean"))
        assert (iso.color_range, iso.color_min, iso.color_max) == ("manual", -9.0, 9.0)
        assert (panel.vmin.value(), panel.vmax.value()) == (-9.0, 9.0)
        # the split's two views: linked by default, the box unlinks them
        link = colour_range_link(scene)
        assert panel.linked.isChecked() and link.enabled
        panel.linked.setChecked(False)
        assert not link.enabled
        panel.linked.setChecked(True)
        assert link.enabled
    finally:
        view.close()
        pl.close()
