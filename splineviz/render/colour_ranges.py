"""Colour ranges shared by the views of one scene: the two halves of a split view colour a
surface over one range (ParaView's linked views).

Each :class:`~splineviz.render.scene.SplineScene` of a link reports the automatic range its
frame of a surface needs (the 2-98 % percentiles of the values it shows,
:func:`splineviz.core.colour_by.scalar_range`); all of them colour the surface over the span
of the reports. Frames of different sizes (or a preview beside an exact frame) hold different
pixels, so their percentiles differ: without the link the same surface showed two colour
scales side by side.
"""

from __future__ import annotations


class ColourRangeLink:
    """The automatic colour ranges of the views of one scene model, shared (see the module
    docstring): each :class:`~splineviz.render.scene.SplineScene` in the link reports the
    range its frame of a surface needs, and every view colours that surface over the span of
    all reports.

    :meth:`set_enabled` (False) unlinks them: each view colours by its own frame. ``listeners``
    are called with ``(key, (lo, hi))`` when the shared range of a surface changes (a panel
    showing the range in use).
    """

    def __init__(self):
        self.enabled = True
        self.listeners: list = []
        self._reports: dict = {}  # key -> {id(scene): (lo, hi)}
        self._scenes: dict = {}  # id(scene) -> scene

    def set_enabled(self, on: bool) -> None:
        """Link (True) or unlink the views' ranges; every view colours its frames again."""
        self.enabled = bool(on)
        for sid, scene in list(self._scenes.items()):
            for key in [k for k, r in self._reports.items() if sid in r]:
                scene.recolour(key)

    def range_of(self, key) -> tuple | None:
        """The shared ``(lo, hi)`` of the surface ``key`` (None: no view reported it)."""
        reports = self._reports.get(key)
        if not reports:
            return None
        return (min(r[0] for r in reports.values()), max(r[1] for r in reports.values()))

    def report(self, scene, key, value: tuple) -> tuple:
        """``scene``'s range ``value`` of the surface ``key``; returns the range to use."""
        before = self.range_of(key)
        self._scenes[id(scene)] = scene
        self._reports.setdefault(key, {})[id(scene)] = tuple(map(float, value))
        after = self.range_of(key)
        if after != before:
            self._changed(key, after, scene)
        return after if self.enabled else tuple(value)

    def forget(self, scene, key=None) -> None:
        """Drop ``scene``'s reports (of ``key``, or all of them when it closes)."""
        keys = list(self._reports) if key is None else [key]
        for k in keys:
            before = self.range_of(k)
            self._reports.get(k, {}).pop(id(scene), None)
            if not self._reports.get(k):
                self._reports.pop(k, None)
            after = self.range_of(k)
            if after != before and after is not None:
                self._changed(k, after, scene)
        if key is None:
            self._scenes.pop(id(scene), None)

    def _changed(self, key, value, source) -> None:
        if self.enabled:
            for sid, other in list(self._scenes.items()):
                if other is not source and sid in self._reports.get(key, {}):
                    other.recolour(key)
        for listener in list(self.listeners):
            listener(key, value)


class FixedRanges(dict):
    """Ranges given per surface key, used as they are: what a copy of a view in another
    window (:func:`~splineviz.render.scene.offscreen_screenshot`) colours by, so that an
    exported picture has the colours on screen. A surface without one keeps its own."""

    def report(self, scene, key, value: tuple) -> tuple:
        return tuple(self.get(key, value))

    def forget(self, scene, key=None) -> None:
        """Nothing to forget: the ranges are fixed."""


def range_key(layer):
    """What identifies a layer's surface across the views of a scene: its node's id."""
    node = getattr(layer, "node", None)
    return node.id if node is not None else id(layer)
