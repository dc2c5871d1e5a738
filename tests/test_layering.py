"""DESIGN.md's import layering, checked by the import-linter contracts in pyproject.toml."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_import_contracts_hold():
    lint = Path(sys.executable).with_name("lint-imports")
    result = subprocess.run([str(lint), "--config", str(ROOT / "pyproject.toml")],
                            cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "BROKEN" not in result.stdout and "KEPT" in result.stdout


def test_core_imports_without_qt_vtk_opencl():
    code = ("import sys, splineviz.core.splines.to_quadratic, splineviz.core.testfunctions, "
            "splineviz.core.bform;"
            "bad=[m for m in sys.modules if m.split('.')[0] in "
            "('PySide6','vtk','vtkmodules','pyvista','pyopencl','pyvistaqt')];"
            "print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
