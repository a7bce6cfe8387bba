"""Issue 28.6/28.8: docs/development.md's layout describes project/ as it is:
every module of plcbuilder/project (the build/ package's too) is named there."""

from pathlib import Path

import plcbuilder.project

ROOT = Path(__file__).resolve().parents[2]


def test_the_layout_names_every_module_of_project():
    text = (ROOT / "docs" / "development.md").read_text(encoding="utf-8")
    layout = text.split("## Layout", 1)[1].split("```")[1]
    entry = layout.split("  project/", 1)[1].split("\n  link/", 1)[0]
    folder = Path(plcbuilder.project.__file__).parent
    for p in sorted(folder.rglob("*.py")):
        if p.name != "__init__.py":
            assert p.name in entry, f"the layout in docs/development.md does not name {p.name}"
    assert "build/" in entry and "build.py" not in entry
