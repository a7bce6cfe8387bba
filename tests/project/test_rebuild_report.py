"""Issue 26.2: an unchanged rebuild through ``plcbuilder build`` prints what
the cold build printed without reading each source file once per diagnostic
(7,300 reads of a thousand files in the benchmark project) or decoding every
procedure's diagnostics three times."""

import io

from plcbuilder.cli import cmd_build, term
from plcbuilder.lang import Diagnostic
from plcbuilder.project import Project, build_project
from plcbuilder.project.build import results

SOURCE = "main()\n{\n" + "".join(f"  v{i} = w{i};\n" for i in range(12)) + "  exit(99);\n};\n"


def _project(root):
    (root / "hardware").mkdir(parents=True)
    (root / "software").mkdir()
    for i in range(3):
        (root / "hardware" / f"M{10 + i}.plc").write_text(SOURCE)
    (root / "plcbuilder.toml").write_text('name = "p"\n')
    return Project.open(root)


def _report(result) -> str:
    out = term.Out("never")
    buf = io.StringIO()
    out.stdout = buf
    cmd_build.report(result, out)
    return buf.getvalue()


def test_an_unchanged_rebuild_reads_each_file_once_for_its_report(tmp_path, monkeypatch):
    project = _project(tmp_path / "p")
    cold = build_project(project)
    cold_text = _report(cold)
    again = build_project(project)
    assert again.reused == 3
    reads = []
    real = results.source_text

    def counting(name, *a, **k):
        reads.append(name)
        return real(name, *a, **k)
    monkeypatch.setattr(results, "source_text", counting)
    decodes = []
    real_decode = Diagnostic.from_dict
    monkeypatch.setattr(Diagnostic, "from_dict", lambda v: decodes.append(1) or real_decode(v))
    text = _report(again)
    def diagnostics(report: str) -> list[str]:          # up to the totals, "(unchanged)" aside
        lines = report.replace(" (unchanged)", "").splitlines()
        return lines[:next(i for i, ln in enumerate(lines) if ln.startswith("hardware total"))]
    assert diagnostics(text) == diagnostics(cold_text)
    assert text.splitlines()[-1].endswith("(0 compiled, 3 unchanged)")
    n_diags = sum(len(pb.diagnostics) for pb in again.procedures)
    assert n_diags == 3 * 24 and "hint:" in text
    assert len(reads) <= 3, reads                 # one read a file, not one a diagnostic
    assert len(decodes) <= n_diags + 3 * 24       # decoded to print, not three times over


def test_an_unchanged_rebuild_prints_the_diagnostics_as_the_compiler_rendered_them(
        tmp_path, monkeypatch):
    """The cache keeps each procedure's diagnostics as the report printed them
    (``shown``): an unchanged rebuild prints that text without reading a source
    or decoding a diagnostic, and it is what the cold build printed; a report
    in colour renders them again; a damaged ``shown`` compiles that procedure
    again."""
    import json

    from plcbuilder.project.build import CACHE_FILE
    project = _project(tmp_path / "p")
    cold_text = _report(build_project(project))
    again = build_project(project)
    reads, decodes = [], []
    monkeypatch.setattr(results, "source_text", lambda *a, **k: reads.append(a))
    monkeypatch.setattr(Diagnostic, "from_dict", lambda v: decodes.append(v))
    text = _report(again)
    assert reads == [] and decodes == []
    assert text.replace(" (unchanged)", "").splitlines()[:-3] == cold_text.splitlines()[:-3]
    monkeypatch.undo()

    doc = json.loads((project.build_dir / CACHE_FILE).read_text())
    shown = doc["procedures"]["hardware/M11"]["shown"]
    assert shown.count(": warning: ") == 24 and shown in cold_text
    colour = term.Out("always")
    colour.stdout = io.StringIO()
    cmd_build.report(build_project(project), colour)
    painted = colour.stdout.getvalue()
    assert "\x1b[" in painted
    import re
    assert shown in re.sub(r"\x1b\[[0-9;]*m", "", painted)

    doc["procedures"]["hardware/M11"]["shown"] = 5
    (project.build_dir / CACHE_FILE).write_text(json.dumps(doc))
    r = build_project(project)
    assert (r.compiled, r.reused) == (1, 2) and not r.get("M11").cached
    assert _report(r).replace(" (unchanged)", "").splitlines()[:-3] == \
        cold_text.splitlines()[:-3]
