"""Undo and redo in the GUI: Qt's ``QUndoStack`` over the scene's commands
(:mod:`splineviz.model.commands`).

Each scene has one :class:`SceneUndo` (:func:`undo_stack`); the panels push their edits to
it and the Edit menu's Undo / Redo (Ctrl+Z / Ctrl+Shift+Z) step through it. While a
slider or a plane widget is dragged (:meth:`SceneUndo.begin_drag` ... :meth:`end_drag`),
consecutive changes of the same properties of one node merge into one step, as ParaView
does; a drag that ends where it started leaves no step.

The history only describes the scene while nothing else adds or removes objects: when that
happens outside a command (a session loaded, the scene replaced by a file, a comparison
copy made by the split view), the history is cleared, so no step can act on objects that
are no longer the ones it changed.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject
from PySide6.QtGui import QUndoCommand, QUndoStack

from splineviz.model import Node, Scene
from splineviz.model.commands import ChangeObjects, Command, SetProperties, remove_objects

#: steps kept: a removed object stays in memory, with its data, while a step can bring it
#: back (ParaView keeps a bounded history too)
UNDO_LIMIT = 100

#: scene -> its undo stack (the stack refers to the scene weakly: it dies with the scene)
_STACKS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def undo_stack(scene: Scene) -> SceneUndo:
    """The undo stack of ``scene`` (made on first use): one per scene, shared by the window's
    panels, its Edit menu and its file commands."""
    stack = _STACKS.get(scene)
    if stack is None:
        stack = _STACKS[scene] = SceneUndo(scene)
    return stack


class _QtCommand(QUndoCommand):
    """A model command on the Qt stack. It is pushed already done (the stack's first
    ``redo`` is skipped): a command that fails is never pushed."""

    def __init__(self, owner: SceneUndo, command: Command, merge_id: int):
        super().__init__(command.text)
        self.owner = owner
        self.command = command
        self._merge_id = merge_id
        self._first = True

    def id(self) -> int:  # noqa: A003 (Qt's name)
        return self._merge_id

    def redo(self) -> None:
        if self._first:
            self._first = False
            return
        self.owner._run(self.command.do)

    def undo(self) -> None:
        self.owner._run(self.command.undo)

    def mergeWith(self, other: QUndoCommand) -> bool:  # noqa: N802 (Qt naming)
        if not isinstance(other, _QtCommand) or not self.command.merge(other.command):
            return False
        # Qt drops a command left obsolete by a merge: a drag back to the start
        self.setObsolete(self.command.obsolete)
        return True


class SceneUndo(QObject):
    """The undo history of one scene (see module docstring).

    Attributes
    ----------
    stack : QUndoStack
        Its ``undoText``/``canUndo`` and the Edit menu's actions follow it.
    """

    def __init__(self, scene: Scene):
        super().__init__()
        self.stack = QUndoStack(self)
        self.stack.setUndoLimit(UNDO_LIMIT)
        self._scene = weakref.ref(scene)
        self._running = 0
        self._drag = 0
        self._dragging = False
        scene.inserted.connect(self._structure_changed)
        scene.removed.connect(self._structure_changed)

    @property
    def scene(self) -> Scene:
        return self._scene()

    # -- pushing ---------------------------------------------------------------------------

    def push(self, command: Command) -> Command:
        """Do ``command`` and make it the next step to undo (merged with the last one while
        a drag lasts). An error (:class:`~splineviz.model.ModelError`) leaves the scene and
        the history as they were."""
        self._run(command.do)
        if command.obsolete:
            return command
        merge_id = -1
        if self._dragging and command.merge_key is not None:
            merge_id = hash((self._drag, command.merge_key)) & 0x7FFFFFFF
        self.stack.push(_QtCommand(self, command, merge_id))
        return command

    def set(self, node: Node, text: str | None = None, **values) -> None:
        """Set properties of ``node`` as one step (unchanged values make no step)."""
        values = {k: v for k, v in values.items() if getattr(node, k) != v}
        if values:
            self.push(SetProperties(self.scene, node, values, text))

    def change(self, text: str, operation: Callable[[], Any]) -> Any:
        """Run ``operation`` (it adds or removes objects) as one step; its result."""
        return self.push(ChangeObjects(self.scene, text, operation)).result

    def remove(self, node: Node) -> None:
        """Remove ``node`` and its dependants as one step."""
        self.push(remove_objects(self.scene, node))

    def _run(self, fn: Callable[[], None]) -> None:
        self._running += 1
        try:
            fn()
        finally:
            self._running -= 1

    # -- drags -------------------------------------------------------------------------------

    def begin_drag(self) -> None:
        """A slider or widget drag starts: its changes merge into one step until
        :meth:`end_drag`."""
        self._drag += 1
        self._dragging = True

    def end_drag(self) -> None:
        self._dragging = False

    # -- history -----------------------------------------------------------------------------

    def undo(self) -> None:
        self.stack.undo()

    def redo(self) -> None:
        self.stack.redo()

    def _structure_changed(self, _node) -> None:
        if not self._running and self.stack.count():
            self.stack.clear()
