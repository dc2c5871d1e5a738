"""The splineviz desktop application (PySide6 + pyvistaqt + superqt).

:func:`splineviz.gui.app.run_gui` opens the main window; everything Qt lives in this package.
"""

from splineviz.gui._pyside_fix import guard_singleton_refcounts

# before any widget exists: PySide6 6.12 calls on Python 3.11 take references from None and
# True, and the process aborts when they run out (see splineviz.gui._pyside_fix)
guard_singleton_refcounts()
