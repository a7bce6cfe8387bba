"""The manual's links hold: README.md and docs/*.md link only to files that exist
and to headings those files have (GitHub's anchors), every image is there, and every
``docs/X.md`` the code cites exists, with the section it names in quotes."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

_FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.M | re.S)
_CODE_SPAN = re.compile(r"(`+)(?!`).*?(?<!`)\1(?!`)", re.S)
# [text](target) and ![alt](target); text and alt may span lines
_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_HEADING = re.compile(r"^#{1,6}[ \t]+(.+?)[ \t#]*$", re.M)
_EXTERNAL = re.compile(r"^[a-z][a-z0-9+.-]*:", re.I)     # http:, https:, mailto:, …


def _prose(text: str) -> str:
    """The text without fenced code blocks (whose `#include` lines are no headings)."""
    return _FENCE.sub("", text)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: the rendered text lowercased, punctuation but
    ``-`` and ``_`` dropped, each space a ``-``."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)     # a link: its text
    text = re.sub(r"<[^>]+>", "", text)                            # inline HTML
    return re.sub(r"[^\w\- ]", "", text.lower()).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every anchor GitHub gives the headings of a Markdown file (repeats get -1, -2, …)."""
    seen: dict[str, int] = {}
    out = set()
    for m in _HEADING.finditer(_prose(path.read_text(encoding="utf-8"))):
        base = slug(m.group(1))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def links(path: Path) -> list[str]:
    prose = _CODE_SPAN.sub("", _prose(path.read_text(encoding="utf-8")))
    return [m.group(1) for m in _LINK.finditer(prose)]


def broken_links(path: Path) -> list[str]:
    """The relative links of one page that point at nothing, each with the reason."""
    broken = []
    for target in links(path):
        if _EXTERNAL.match(target):
            continue
        file_part, _, anchor = target.partition("#")
        dest = (path.parent / file_part).resolve() if file_part else path
        if not dest.exists():
            broken.append(f"{target}: no file {dest.relative_to(ROOT) if dest.is_relative_to(ROOT) else dest}")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{target}: no heading with the anchor #{anchor} in {dest.name}")
    return broken


def test_the_manual_has_its_chapters():
    names = {p.name for p in PAGES}
    for chapter in ("ide", "language", "projects", "controller", "machine", "protocol",
                    "development"):
        assert f"{chapter}.md" in names
    front = links(ROOT / "README.md")
    assert "docs/images/ide-homing.png" in front
    for chapter in sorted(names - {"README.md"} - _NOT_YET_ON_THE_FRONT_PAGE):
        assert f"docs/{chapter}" in front, f"README.md does not link to docs/{chapter}"


#: Chapters whose link on README.md's list the maintainer adds (helpers do not edit
#: README.md); remove a name once README.md links it.
_NOT_YET_ON_THE_FRONT_PAGE = {"debugging.md"} - {
    m.group(1) for m in re.finditer(r"docs/([\w-]+\.md)", (ROOT / "README.md").read_text(
        encoding="utf-8"))}


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_and_images_exist(page):
    assert links(page) or page.name != "README.md"
    broken = broken_links(page)
    assert not broken, "broken links:\n" + "\n".join(broken)


# docs/controller.md, "Timing rules" / docs/controller.md ("The JSON object") /
# docs/controller.md, 'Scenario files'
_CITATION = re.compile(r"docs/([\w-]+\.md)(?:[\s,(]*[\"'“]([^\"'”\n]{1,80})[\"'”])?")


def citations() -> list[tuple[str, str, str | None]]:
    """(where, file, section or None) for every docs/X.md the code cites."""
    out = []
    here = Path(__file__).resolve()
    for folder in ("plcbuilder", "scripts", "tests"):
        for f in sorted((ROOT / folder).rglob("*")):
            if (not f.is_file() or f.resolve() == here
                    or f.suffix not in {".py", ".toml", ".md", ".txt", ".xml", ".h", ".plc", ""}):
                continue
            try:
                text = f.read_text(encoding="utf-8")
            except UnicodeDecodeError:
                continue
            for m in _CITATION.finditer(text):
                line = text.count("\n", 0, m.start()) + 1
                out.append((f"{f.relative_to(ROOT)}:{line}", m.group(1), m.group(2)))
    return out


def test_docs_cited_by_the_code_exist_with_their_sections():
    found = citations()
    assert any(section == "Timing rules" for _, _, section in found)
    problems = []
    for where, name, section in found:
        doc = ROOT / "docs" / name
        if not doc.exists():
            problems.append(f"{where}: docs/{name} does not exist")
        elif section is not None and slug(section) not in anchors(doc):
            problems.append(f"{where}: docs/{name} has no section {section!r}")
    assert not problems, "\n".join(problems)


def test_the_anchor_rules():
    assert slug("Projects, Build All and the `eeprom.rom` image") == \
        "projects-build-all-and-the-eepromrom-image"
    assert slug("`--strict`: controller compatibility") == "--strict-controller-compatibility"
    assert slug("`#define`") == "define"
    assert slug("plc-variables.xml") == "plc-variablesxml"
    assert slug("`[[inputs]]`: what an input pin reads") == "inputs-what-an-input-pin-reads"
