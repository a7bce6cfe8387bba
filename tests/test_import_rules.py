"""The layering of DESIGN.md, checked exactly: which package may import which,
and the core never loads Qt.

DESIGN.md's rules, as written: ``_support``, ``bytecode`` and ``diagnostics``
import nothing of ours but ``_support``; lang → diagnostics, bytecode;
controller → bytecode; trace → controller; image → bytecode; project → lang,
bytecode, image; testing → project, controller, trace; link → controller, image,
trace; lsp → lang, project; dap → link, project; api is the facade over all of
these; cli → api, link; ide → api, project, link, lang, trace, testing; nothing
imports ide, cli, lsp or dap. Every package may use ``_support`` (stdlib-only
helpers "used everywhere").

The exceptions are the commands that start a front end: ``cli/cmd_gui.py``
(the IDE), ``cli/cmd_lsp.py`` (the language server) and ``cli/cmd_dap.py``
(the debug adapter).

Read literally: an arrow is a direct import. A package reaches what its
neighbours offer only through them (project gets the Diagnostic type from lang,
which produces diagnostics; the IDE gets the ABI tables and events from api).
The exceptions are the commands that start a front end (above).
"""

import ast
import subprocess
import sys
from pathlib import Path

import plcbuilder

PKG = Path(plcbuilder.__file__).parent
FACADE_OVER = {"_support", "bytecode", "diagnostics", "lang", "controller", "trace", "image",
               "project", "testing", "link"}
ALLOWED = {
    "_support": set(),
    "bytecode": set(),
    "diagnostics": set(),
    "lang": {"diagnostics", "bytecode"},
    "controller": {"bytecode"},
    "trace": {"controller"},
    "image": {"bytecode"},
    "project": {"lang", "bytecode", "image"},
    "testing": {"project", "controller", "trace"},
    "link": {"controller", "image", "trace"},
    "lsp": {"lang", "project"},
    "dap": {"link", "project"},
    "api": FACADE_OVER,
    "cli": {"api", "link"},
    "ide": {"api", "project", "link", "lang", "trace", "testing"},
    "__init__": set(),
    "__main__": {"cli"},
}
NOBODY_IMPORTS = {"ide", "cli", "lsp", "dap"}
#: The commands that start a front end, and the one each may import.
FRONT_END_COMMANDS = {"cli/cmd_gui.py": "ide", "cli/cmd_lsp.py": "lsp", "cli/cmd_dap.py": "dap"}
QT = ("PySide6", "pyqtgraph", "pyside6_scintilla", "shiboken6")


def _imports(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "plcbuilder":          # from plcbuilder import api
                for a in node.names:
                    yield f"plcbuilder.{a.name}"
            else:
                yield node.module
        elif isinstance(node, ast.ImportFrom) and node.level:
            yield from ()                            # relative: inside its own package


def _top(py: Path) -> str:
    return py.relative_to(PKG).parts[0].removesuffix(".py")


def test_every_part_of_the_package_has_a_rule():
    tops = {_top(py) for py in PKG.rglob("*.py")}
    assert tops <= set(ALLOWED), f"no rule for {sorted(tops - set(ALLOWED))}"


def test_packages_import_only_what_design_allows():
    problems = []
    for py in sorted(PKG.rglob("*.py")):
        top = _top(py)
        rel = py.relative_to(PKG)
        for mod in _imports(py):
            parts = mod.split(".")
            if parts[0] == "plcbuilder" and len(parts) > 1:
                target = parts[1]
                if target == top or target == "_support" or target.startswith("__"):
                    continue                         # itself, the helpers, __version__
                if FRONT_END_COMMANDS.get(rel.as_posix()) == target:
                    continue                         # the command that starts a front end
                if target not in ALLOWED[top]:
                    problems.append(f"{rel}: imports {mod}")
            if top != "ide" and parts[0] in QT:
                problems.append(f"{rel}: imports {mod} (only plcbuilder.ide may use Qt)")
    assert not problems, "\n".join(problems)


def test_nothing_imports_the_front_ends():
    for py in PKG.rglob("*.py"):
        top = _top(py)
        for mod in _imports(py):
            parts = mod.split(".")
            if parts[0] == "plcbuilder" and len(parts) > 1 and parts[1] in NOBODY_IMPORTS:
                ok = parts[1] == top or FRONT_END_COMMANDS.get(
                    py.relative_to(PKG).as_posix()) == parts[1] or top == "__main__"
                assert ok, f"{py.relative_to(PKG)} imports {mod}"


def test_support_uses_the_standard_library_only():
    for py in (PKG / "_support").rglob("*.py"):
        for mod in _imports(py):
            assert mod.split(".")[0] != "plcbuilder", f"{py.name} imports {mod}"
            assert mod.split(".")[0] in sys.stdlib_module_names or mod == "__future__", \
                f"{py.name} imports {mod}"


def test_importing_the_cli_and_core_loads_no_qt():
    code = ("import sys, plcbuilder.cli.main as m, plcbuilder.api, plcbuilder.lang.pipeline;"
            "m.build_parser();"
            "bad=[k for k in sys.modules if k.split('.')[0] in %r]; print(bad); "
            "raise SystemExit(1 if bad else 0)" % (QT,))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
