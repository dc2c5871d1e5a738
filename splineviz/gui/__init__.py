"""The splineviz desktop application (PySide6 + pyvistaqt + superqt).

:func:`splineviz.gui.app.run_gui` opens the main window; everything Qt lives in this package.
"""
