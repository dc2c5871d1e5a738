"""Docked panels of the main window, each a view of the scene model (testable with qtbot on
a bare :class:`splineviz.model.Scene`, without a window)."""

from splineviz.gui.panels.analysis import AnalysisPanel
from splineviz.gui.panels.clipping import ClippingPanel, PlaneWidgets
from splineviz.gui.panels.data import DataPanel
from splineviz.gui.panels.isosurface import IsosurfacePanel
from splineviz.gui.panels.log import LogPanel
from splineviz.gui.panels.remesh import RemeshPanel
from splineviz.gui.panels.smoothing import Smoother, SmoothingPanel
from splineviz.gui.panels.volume_rendering import VolumeRenderingPanel

__all__ = ["AnalysisPanel", "ClippingPanel", "DataPanel", "IsosurfacePanel", "LogPanel",
           "PlaneWidgets", "RemeshPanel", "Smoother", "SmoothingPanel", "VolumeRenderingPanel"]
