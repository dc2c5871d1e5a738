"""A plugin spline model whose evaluation sleeps until the test lets it go: the slow model of
the tests that no model, however slow, makes the GUI thread wait (issue 26)."""

from __future__ import annotations

import contextlib
import threading

from splineviz import plugins
from splineviz.core.splines import MODELS
from splineviz.core.splines.trilinear import TrilinearSpline

#: set when a test ends (or lets the model go): the evaluations it is stuck in return
RELEASE = threading.Event()


#: the sleeping model's name in the model registry
NAME = "sleeptest-slow"


class SleepingSpline(TrilinearSpline):
    """The trilinear spline, but each evaluation waits for :data:`RELEASE`."""

    model = NAME
    #: the longest an evaluation waits (set by :func:`sleeping_model`)
    max_sleep_s = 300.0

    def index_derivatives(self, upoints, order):
        RELEASE.wait(self.max_sleep_s)
        return super().index_derivatives(upoints, order)


@contextlib.contextmanager
def sleeping_model(label: str, max_sleep_s: float):
    """Register :class:`SleepingSpline` through the plugin API as model :data:`NAME` (its
    evaluations wait at most ``max_sleep_s``); yields the name and restores the model
    registry afterwards. The plugin API keeps a model as "module:Class", so the class lives
    at module level."""
    SleepingSpline.max_sleep_s = float(max_sleep_s)
    MODELS.names()  # the installed plugins first: the snapshot restores them
    snapshot = dict(MODELS)
    api = plugins.PluginAPI("sleeptest")
    api.add_model(NAME, SleepingSpline, label=label, degree=1, smoothness="C0")
    api._commit()
    RELEASE.clear()
    try:
        yield NAME
    finally:
        RELEASE.set()
        MODELS.clear()
        MODELS.update(snapshot)
