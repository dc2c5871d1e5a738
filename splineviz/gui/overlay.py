"""What a view is computing, written over it: :class:`ViewOverlay`.

A Qt label on top of the 3-D view's widget, not VTK text: setting its text costs no render
of the scene, and a VTK text actor's first frame in a new OpenGL context took 50-100 ms of
the GUI thread (its font texture and shaders), just when an exact frame began to take long.
Screen captures of the window show it; the scene's own renders and screenshots do not.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel

#: the label's look: light text on a translucent dark box, top left of the view
STYLE = ("QLabel { color: rgb(255, 236, 140); background: rgba(13, 13, 20, 180); "
         "padding: 3px 6px; font-size: 14px; }")


class ViewOverlay:
    """Lines of text in the top left corner of ``widget``, hidden when empty.

    Parameters
    ----------
    widget : QWidget
        The view's widget; the label is its child and lets the mouse through.
    """

    def __init__(self, widget):
        self.label = QLabel(widget)
        self.label.setStyleSheet(STYLE)
        self.label.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.label.setTextFormat(Qt.TextFormat.PlainText)
        # lines wrap inside the view (a four-up pane or a split half is narrow)
        self.label.setWordWrap(True)
        self.label.move(6, 6)
        self.label.hide()

    @property
    def text(self) -> str:
        return self.label.text() if self.visible else ""

    @property
    def visible(self) -> bool:
        return not self.label.isHidden()

    def set_text(self, text: str) -> None:
        """Show ``text`` ("" hides the overlay)."""
        if text == self.text:
            return
        self.label.setText(text)
        self.label.setMaximumWidth(max(self.label.parentWidget().width() - 12, 60))
        self.label.adjustSize()
        self.label.setVisible(bool(text))
