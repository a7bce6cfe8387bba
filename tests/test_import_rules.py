"""The layering of DESIGN.md, checked: which package may import which, and the
core never loads Qt."""

import ast
import subprocess
import sys
from pathlib import Path

import plcbuilder

PKG = Path(plcbuilder.__file__).parent
ALLOWED = {
    "_support": set(),
    "bytecode": set(),
    "diagnostics": set(),
    "lang": {"diagnostics", "bytecode"},
    "controller": {"bytecode"},
    "image": {"bytecode"},
    "project": {"lang", "bytecode", "image", "diagnostics", "controller"},
    "link": {"controller", "image", "bytecode"},
    "cli": {"api", "link", "diagnostics", "bytecode", "lang", "project", "image", "controller",
            "simulate", "ide"},
    "ide": {"api", "project", "link", "lang", "bytecode", "diagnostics", "controller", "image",
            "simulate"},
}
QT = ("PySide6", "pyqtgraph", "pyside6_scintilla", "shiboken6")


def _imports(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module


def test_packages_import_only_what_design_allows():
    problems = []
    for py in PKG.rglob("*.py"):
        rel = py.relative_to(PKG)
        top = rel.parts[0].removesuffix(".py")
        if top not in ALLOWED:
            continue
        for mod in _imports(py):
            if mod.startswith("plcbuilder."):
                target = mod.split(".")[1]
                if target != top and target not in ALLOWED[top] and target != "_support":
                    problems.append(f"{rel}: imports {mod}")
            if top != "ide" and mod.split(".")[0] in QT:
                problems.append(f"{rel}: imports {mod} (only plcbuilder.ide may use Qt)")
    assert not problems, "\n".join(problems)


def test_cli_gui_command_is_the_only_cli_module_that_may_reach_the_ide():
    for py in (PKG / "cli").glob("*.py"):
        if py.name == "cmd_gui.py":
            continue
        for mod in _imports(py):
            assert not mod.startswith("plcbuilder.ide"), f"{py.name} imports {mod}"


def test_nothing_imports_cli_or_ide_except_their_own():
    for py in PKG.rglob("*.py"):
        top = py.relative_to(PKG).parts[0]
        for mod in _imports(py):
            if mod.startswith("plcbuilder.cli"):
                assert top in ("cli", "__main__.py"), f"{py} imports {mod}"
            if mod.startswith("plcbuilder.ide"):
                assert top in ("ide", "cli"), f"{py} imports {mod}"


def test_importing_the_cli_and_core_loads_no_qt():
    code = ("import sys, plcbuilder.cli.main as m, plcbuilder.api, plcbuilder.lang.compiler;"
            "m.build_parser();"
            "bad=[k for k in sys.modules if k.split('.')[0] in %r]; print(bad); "
            "raise SystemExit(1 if bad else 0)" % (QT,))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
