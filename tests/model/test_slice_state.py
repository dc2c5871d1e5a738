"""The slice views' state (splineviz.model.slices.SliceViewNode): layouts, a crosshair kept in
the volume and on its grid planes by the wheel, window / level from the data."""

import numpy as np
import pytest

import splineviz as sv
from splineviz.model import ModelError
from splineviz.model.slices import AXES, IN_PLANE, SliceViewNode


@pytest.fixture
def volume():
    data = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6)
    return sv.Volume(data, spacing=(0.5, 1.0, 2.0), origin=(10.0, 0.0, -3.0))


def test_layouts_show_their_slices():
    st = SliceViewNode()
    assert st.shown == ()
    st.layout = "four-up"
    assert st.shown == ("axial", "coronal", "sagittal")
    st.update(layout="one-slice", single="coronal")
    assert st.shown == ("coronal",)
    with pytest.raises(ModelError, match="layout"):
        st.layout = "nine-up"
    assert st.layout == "one-slice"
    # the in-plane axes are the two others, in order
    for name, axis in AXES.items():
        assert sorted((axis, *IN_PLANE[name])) == [0, 1, 2]


def test_fit_centres_the_crosshair_and_windows_the_data(volume):
    st = SliceViewNode()
    st.fit(volume)
    assert st.crosshair == (11.0, 2.0, 3.0)  # sample (2, 2, 3)
    lo, hi = np.percentile(volume.data, (2, 98))
    assert st.window == pytest.approx(hi - lo) and st.level == pytest.approx((lo + hi) / 2)
    assert st.index("axial", volume) == 3


def test_wheel_steps_land_on_grid_planes_inside_the_volume(volume):
    st = SliceViewNode()
    st.fit(volume)
    events = []
    st.events.crosshair.connect(events.append)
    st.scroll("axial", 1, volume)
    assert st.crosshair == (11.0, 2.0, 5.0) and len(events) == 1
    st.scroll("axial", 100, volume)
    assert st.position("axial") == volume.bounds[2][1]
    st.scroll("sagittal", -100, volume)
    assert st.position("sagittal") == 10.0
    # off the grid (a click), the wheel snaps to the nearest plane and steps from there
    st.move_to((10.3, 2.6, 1.0), volume)
    st.scroll("coronal", 1, volume)
    assert st.crosshair == (10.3, 4.0, 1.0)


def test_move_to_keeps_the_crosshair_in_the_box(volume):
    st = SliceViewNode()
    st.move_to((-50.0, 2.5, 1e6), volume)
    assert st.crosshair == (10.0, 2.5, volume.bounds[2][1])
