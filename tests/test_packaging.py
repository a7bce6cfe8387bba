"""The package works from an installed wheel: resources and the grammar are
package data, and the pygments lexer is registered as an entry point."""

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                        "-q", "-w", str(out), str(ROOT)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.fail(f"building the wheel failed:\n{r.stdout}\n{r.stderr}")
    (whl,) = out.glob("plcbuilder-*.whl")
    return whl


def test_wheel_ships_resources_and_grammar(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "plcbuilder/resources/include/pins.h" in names
    assert "plcbuilder/lang/grammar.lark" in names
    assert "plcbuilder/resources/machine/default.toml" in names


def test_wheel_ships_every_module(wheel):
    """Every module of the package is in the wheel, even one in a folder named
    like an output folder (plcbuilder/project/build/, which .gitignore's
    ``build/`` would hide)."""
    names = set(zipfile.ZipFile(wheel).namelist())
    package = ROOT / "plcbuilder"
    modules = {p.relative_to(ROOT).as_posix() for p in package.rglob("*.py")}
    assert "plcbuilder/project/build/cache.py" in modules
    assert sorted(modules - names) == []


def test_wheel_declares_the_console_script_and_lexer(wheel):
    z = zipfile.ZipFile(wheel)
    (ep,) = [n for n in z.namelist() if n.endswith("entry_points.txt")]
    text = z.read(ep).decode()
    assert "plcbuilder = plcbuilder.cli.main:main" in text
    assert "plc = plcbuilder.lang.highlight:PlcLexer" in text


def test_installed_wheel_compiles_with_builtin_headers(wheel, tmp_path):
    target = tmp_path / "site"
    with zipfile.ZipFile(wheel) as z:
        z.extractall(target)
    code = ("import sys; sys.path.insert(0, %r); import plcbuilder.api as a; "
            "r=a.compile_source('#include pins.h\\nmain(){ portset(OUTPUT_SPINDLE); exit(99); };');"
            "print(a.__file__); raise SystemExit(0 if r.ok else 1)" % str(target))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert str(target) in r.stdout


def test_wheel_ships_the_manual_for_help(wheel):
    """Help → Manual in an installed IDE reads share/plcbuilder/docs (plcbuilder.ide.help)."""
    names = set(zipfile.ZipFile(wheel).namelist())
    data = "plcbuilder-0.1.0.data/data/share/plcbuilder/docs/"
    for page in sorted((ROOT / "docs").glob("*.md")):
        assert data + page.name in names
    for image in sorted((ROOT / "docs" / "images").glob("*")):
        assert data + "images/" + image.name in names


def test_installed_wheel_parses_with_its_shipped_tables(wheel, tmp_path):
    """Issue 26.1: the wheel carries the parse tables (lang/grammar_tables.py)
    and the default machine's data: an installed package compiles and loads
    the default machine with lark and tomllib unavailable, writing nothing."""
    target = tmp_path / "site"
    with zipfile.ZipFile(wheel) as z:
        z.extractall(target)
        assert "plcbuilder/lang/grammar_tables.py" in z.namelist()
        assert "plcbuilder/controller/default_machine_data.py" in z.namelist()
    before = sorted(p.relative_to(target) for p in target.rglob("*"))
    code = ("import sys; sys.dont_write_bytecode = True; sys.path.insert(0, %r)\n"
            "sys.modules['lark'] = None; sys.modules['tomllib'] = None\n"
            "import plcbuilder.api as a\n"
            "r = a.compile_source('#include pins.h\\nmain(){ x = (1 + ; exit(99); };')\n"
            "assert [d.code for d in r.errors] == ['syntax'], r.diagnostics\n"
            "from plcbuilder.controller.machine_config import default_machine\n"
            "print(a.__file__, default_machine().name)" % str(target))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert str(target) in r.stdout
    assert sorted(p.relative_to(target) for p in target.rglob("*")) == before
