"""An isosurface layer never makes the GUI thread wait (issue 26): while a worker is stuck in
the exact frame of a model that never finishes, a non-blocking preview comes at once from a
cheaper caster, and a switch back to a kernel model casts with casters of its own."""

import threading
import time

import numpy as np
import pytest
from sleeping_model import RELEASE, sleeping_model

from splineviz.core.camera import Camera
from splineviz.core.volume import Volume
from splineviz.render.isosurface import COARSE_TO_FINE, IsosurfaceLayer, ViewState

#: a non-blocking call must return this soon (generous: a busy 2-core machine)
NO_WAIT_S = 10.0


@pytest.fixture
def slow_model():
    with sleeping_model("Sleeping", 120.0) as name:
        yield name


@pytest.fixture
def layer():
    x = np.linspace(-1.0, 1.0, 12)
    data = np.add.outer(np.add.outer(x ** 2, x ** 2), x ** 2)
    layer = IsosurfaceLayer(Volume(data), model="trilinear", isovalue=0.6, device="cpu")
    yield layer
    layer.close()


def _view(distance=30.0):
    return ViewState(Camera((5.5, -distance, 5.5), (5.5, 5.5, 5.5)), (64, 48))


def test_a_stuck_exact_frame_never_holds_up_a_preview_or_another_model(layer, slow_model):
    view = _view()
    assert layer.compute(view).final  # the trilinear caster exists now
    layer.set_model(slow_model)
    assert layer.exact_scales() == COARSE_TO_FINE

    stuck = threading.Thread(target=layer.compute, args=(view,), daemon=True)
    stuck.start()
    time.sleep(0.2)
    assert stuck.is_alive()

    # the GUI thread's preview of the new state: at once, from the cheaper kernel caster
    # (at a size it has cast: a new one compiles its kernel), not coloured (no evaluation
    # of the sleeping spline)
    layer.set_color_by("gradient-magnitude")
    assert layer.compute(_view(31.0), scale=0.5, preview=True, blocking=False) is None
    t = time.perf_counter()
    rf = layer.compute(_view(31.0), scale=1.0, preview=True, blocking=False)
    assert time.perf_counter() - t < NO_WAIT_S
    assert rf is not None and rf.model == "trilinear" and rf.path == "preview"
    assert rf.state == layer.state and not rf.final and rf.scalars is None
    assert layer.compute(_view(31.0), scale=0.5, preview=True) is not None  # in a worker
    rf = layer.compute(_view(32.0), scale=0.5, preview=True, blocking=False)
    assert rf is not None and rf.model == "trilinear"
    # an exact frame of the sleeping model is not made in the GUI thread
    t = time.perf_counter()
    assert layer.compute(view, blocking=False) is None
    assert time.perf_counter() - t < NO_WAIT_S

    # back to a kernel model while the worker is still stuck: its own caster and locks
    layer.set_color_by("none")
    layer.set_model("cubic-c1")
    done = {}
    worker = threading.Thread(target=lambda: done.setdefault("rf", layer.compute(view)),
                              daemon=True)
    worker.start()
    worker.join(60.0)
    assert not worker.is_alive(), "the new model's frame waited for the stuck one"
    assert done["rf"].final and done["rf"].model == "cubic-c1"
    assert done["rf"].state == layer.state
    assert stuck.is_alive()
    RELEASE.set()
    stuck.join(60.0)
