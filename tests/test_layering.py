"""The import layering of docs/architecture.md, checked by the import-linter contracts in
pyproject.toml."""

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


def _import_cycles(graph) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan's algorithm, iterative)."""
    index, low, on_stack, stack, groups = {}, {}, set(), [], []
    for root in sorted(graph.modules):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.find_modules_directly_imported_by(root))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            module, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(
                        graph.find_modules_directly_imported_by(child)))))
                elif child in on_stack:
                    low[module] = min(low[module], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[module])
            if low[module] == index[module]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == module:
                        break
                if len(group) > 1:
                    groups.append(sorted(group))
    return groups


def test_no_import_cycles_between_modules():
    """No two modules of splineviz import each other, directly or around a longer loop.

    Every import statement counts, also one inside a function (a "lazy" import closes a cycle
    as surely as one at the top; it only moves the failure to run time). Imports under
    ``if TYPE_CHECKING:`` do not count: they never run. Package ``__init__`` modules get no
    exemption: importing ``splineviz.io.opening`` runs ``splineviz/io/__init__.py`` first, so a
    module that imports a name from its own package while the package's ``__init__`` imports
    that module is a real cycle (import the name from the module that defines it instead).
    """
    import grimp

    graph = grimp.build_graph("splineviz", exclude_type_checking_imports=True, cache_dir=None)
    cycles = _import_cycles(graph)
    lines = []
    for group in cycles:
        members = set(group)
        for importer in group:
            for imported in sorted(graph.find_modules_directly_imported_by(importer) & members):
                for detail in graph.get_import_details(importer=importer, imported=imported):
                    lines.append(f"{importer}:{detail['line_number']} imports {imported}")
    assert not cycles, "import cycles:\n" + "\n".join(lines)
