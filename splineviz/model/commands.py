"""Undoable edits of a scene: plain-Python commands with :meth:`~Command.do` and
:meth:`~Command.undo` (no Qt).

Every edit a user makes in the panels is one of two commands, applied through the nodes
and :class:`~splineviz.model.Scene` so that every view follows (the panels, the VTK scene,
the autosaver):

* :class:`SetProperties` -- new values of properties of one node (isovalue, model, colour,
  opacity, material, colour-by, a clip plane's pose, smoothing sigma, visibility...);
  consecutive ones of the same node and properties merge into one step while a slider or
  a plane widget is dragged (:attr:`Command.merge_key`);
* :class:`ChangeObjects` -- objects added or removed by an operation (add an isosurface, a
  clip plane, a cross section, a remeshed mesh, a file opened beside the others; remove an
  object with what depends on it). Undo puts a removed object back with its id, its data
  and its dependants (a volume's isosurfaces and planes, an isosurface's sections), in its
  place in the scene's order.

A stack of commands (Qt's ``QUndoStack`` in the GUI, :mod:`splineviz.gui.undo`) calls
``do`` once and then ``undo``/``do`` as the user steps back and forth; scripts and tests
may call them directly.

Examples
--------
>>> import splineviz as sv
>>> from splineviz.core import testfunctions as tf
>>> from splineviz.model import Scene
>>> scene = Scene()
>>> vol = scene.add_volume(sv.Volume.from_function(tf.ml, (9, 9, 9), tf.ml.domain), "ML",
...                        isovalue=0.5)
>>> iso = scene.isosurfaces[0]
>>> edit = SetProperties(scene, iso, {"isovalue": 0.25})
>>> edit.do(); iso.isovalue
0.25
>>> edit.undo(); iso.isovalue
0.5
>>> removal = remove_objects(scene, vol)
>>> removal.do(); len(scene)
0
>>> removal.undo(); [n.id for n in scene]
['volume1', 'isosurface1']
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable
from typing import Any

from splineviz.model.nodes import ModelError, Node
from splineviz.model.scene import Scene


def _in_scene(scene: Scene, node: Node) -> bool:
    """Whether ``node`` itself (not another object with its id) is in ``scene``."""
    return node.id in scene and scene.get(node.id) is node


def _fields(node: Node) -> dict:
    """The node's saved fields (properties, references, origin; not its data), copied."""
    return {k: copy.deepcopy(getattr(node, k)) for k, f in type(node).model_fields.items()
            if not f.exclude and k != "id"}


class Command(ABC):
    """One undoable edit of a scene.

    Attributes
    ----------
    text : str
        What the Edit menu calls it ("Undo <text>").
    merge_key : hashable or None
        Commands with equal keys pushed one after another while a drag lasts merge into
        one step (:meth:`merge`); None never merges.
    """

    text: str = ""
    merge_key: Hashable | None = None

    @abstractmethod
    def do(self) -> None:
        """Apply the edit (the first time, and again on redo)."""

    @abstractmethod
    def undo(self) -> None:
        """Put the scene back as it was before :meth:`do`."""

    def merge(self, other: Command) -> bool:
        """Take ``other`` (done after this one, same :attr:`merge_key`) into this command;
        False: they stay two steps."""
        return False

    @property
    def obsolete(self) -> bool:
        """Whether the command changes nothing (a drag that ended where it started)."""
        return False


class SetProperties(Command):
    """New values of properties of one node, set together (listeners hear of them once
    all are set; a bad value raises :class:`ModelError` and changes nothing).

    Parameters
    ----------
    scene : Scene
    node : Node
        A node of ``scene``.
    values : dict
        ``{property name: new value}``.
    text : str, optional
        Menu text; default "Change <properties> of <node name>".
    """

    def __init__(self, scene: Scene, node: Node, values: dict, text: str | None = None):
        if not _in_scene(scene, node):
            raise ModelError(f"{node.kind} {node.id!r} is not in the scene")
        unknown = [k for k in values if k not in type(node).model_fields]
        if unknown:
            raise ModelError(f"{node.kind} {node.id!r} has no property {unknown[0]!r}")
        self.scene = scene
        self.node = node
        self.new = dict(values)
        self.old = {k: copy.deepcopy(getattr(node, k)) for k in values}
        self.text = text or f"Change {', '.join(values).replace('_', ' ')} of {node.name}"
        self.merge_key = ("set", node.id, tuple(sorted(values)))

    def _check(self) -> None:
        if not _in_scene(self.scene, self.node):
            raise ModelError(f"{self.node.kind} {self.node.id!r} is no longer in the scene")

    def do(self) -> None:
        self._check()
        self.node.update(self.new)

    def undo(self) -> None:
        self._check()
        self.node.update(self.old)

    def merge(self, other: Command) -> bool:
        if not (isinstance(other, SetProperties) and other.node is self.node
                and other.new.keys() == self.new.keys()):
            return False
        self.new = dict(other.new)
        return True

    @property
    def obsolete(self) -> bool:
        return all(_same(self.old[k], self.new[k]) for k in self.new)


def _same(a: Any, b: Any) -> bool:
    """Equal as the node stores them (tuples and lists of numbers compare alike)."""
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


class ChangeObjects(Command):
    """Objects added to or removed from the scene by ``operation`` (and the properties it
    changed on the others), undone and redone without running it again: a remeshed mesh
    comes back as the same node, with its id and data.

    Parameters
    ----------
    scene : Scene
    text : str
        Menu text ("Add isosurface", "Remove volume1"...).
    operation : callable
        ``operation()`` makes the change on ``scene`` when :meth:`do` runs the first time;
        its return value is kept as :attr:`result`.
    """

    def __init__(self, scene: Scene, text: str, operation: Callable[[], Any]):
        self.scene = scene
        self.text = text
        self.operation = operation
        self.result = None
        self._done_once = False
        #: (index in the scene's order, node, fields) of the objects the operation removed
        #: (as they were) and added (as they became)
        self.removed: list[tuple[int, Node, dict]] = []
        self.added: list[tuple[int, Node, dict]] = []
        #: node -> (fields before, fields after) of the objects it changed and kept
        self.changed: dict[str, tuple[Node, dict, dict]] = {}
        self.selection: tuple[Node | None, Node | None] = (None, None)

    def do(self) -> None:
        if self._done_once:
            self._apply(self.removed, self.added, after=True)
            return
        before = [(n, _fields(n)) for n in self.scene]
        selected = self.scene.selected
        self.result = self.operation()
        self._done_once = True
        after = [(n, _fields(n)) for n in self.scene]
        before_ids = {id(n) for n, _ in before}
        after_ids = {id(n) for n, _ in after}
        self.removed = [(i, n, f) for i, (n, f) in enumerate(before) if id(n) not in after_ids]
        self.added = [(i, n, f) for i, (n, f) in enumerate(after) if id(n) not in before_ids]
        fields_after = {id(n): f for n, f in after}
        for n, f in before:
            g = fields_after.get(id(n))
            if g is not None and g != f:
                old = {k: v for k, v in f.items() if g[k] != v}
                self.changed[n.id] = (n, old, {k: g[k] for k in old})
        self.selection = (selected, self.scene.selected)

    def undo(self) -> None:
        self._apply(self.added, self.removed, after=False)

    def _apply(self, drop, restore, *, after: bool) -> None:
        """Remove the objects ``drop``, put back those of ``restore`` in their places with
        their fields, and set the properties of the kept objects changed by the operation
        (to their values after it when ``after``, else before)."""
        scene = self.scene
        for _, node, _ in reversed(drop):
            if _in_scene(scene, node):
                scene.remove(node)
        for index, node, fields in restore:
            if node.id in scene:
                raise ModelError(f"cannot put {node.kind} {node.id!r} back: the scene has "
                                 "another object with its id")
            node.update(fields)
            scene.add(node, index=index)
        for node, old, new in self.changed.values():
            if _in_scene(scene, node):
                node.update(new if after else old)
        selected = self.selection[1 if after else 0]
        scene.select(selected if selected is not None and _in_scene(scene, selected)
                     else None)

    @property
    def obsolete(self) -> bool:
        return self._done_once and not (self.removed or self.added or self.changed)


def add_objects(scene: Scene, text: str, make: Callable[[], Any]) -> ChangeObjects:
    """The command that adds what ``make()`` adds (its result: :attr:`ChangeObjects.result`)."""
    return ChangeObjects(scene, text, make)


def remove_objects(scene: Scene, node: Node) -> ChangeObjects:
    """The command that removes ``node`` and what depends on it (:meth:`Scene.remove`)."""
    if not _in_scene(scene, node):
        raise ModelError(f"{node.kind} {node.id!r} is not in the scene")
    return ChangeObjects(scene, f"Remove {node.name}", lambda: scene.remove(node))
