"""The main window the GUI tests drive."""

import pytest


@pytest.fixture
def window(request, qtbot, tmp_path):
    """A shown 900x560 main window whose view casts frames of the test module's ``SIZE``
    (default 160x120); recent files and settings go to a private folder, not the user's; the
    window is closed once its jobs are idle."""
    from PySide6.QtCore import QSettings

    from splineviz.gui.main_window import MainWindow

    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope, str(tmp_path))
    w = MainWindow(size=getattr(request.module, "SIZE", (160, 120)))
    qtbot.addWidget(w)
    w.resize(900, 560)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.wait_idle()
    w.close()
