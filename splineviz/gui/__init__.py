"""The splineviz desktop application (PySide6 + pyvistaqt + superqt).

:func:`splineviz.gui.app.run_gui` opens the main window; everything Qt lives in this package.
"""

from splineviz.gui._pyside_fix import guard_none_refcount

# before any widget exists: every PySide6 6.12 void call on Python 3.11 takes a reference
# from None, and the process aborts when they run out (see splineviz.gui._pyside_fix)
guard_none_refcount()
