"""The language server's analysis in-process: incremental edits as LSP counts
them, which documents are PLC, what may be read, the incremental compile."""

from __future__ import annotations

from lsprotocol import types as T

from plcbuilder.api import compile_source
from plcbuilder.lsp.access import Access
from plcbuilder.lsp.analysis import Analysis, uri_path
from plcbuilder.lsp.features import call_snippet

from tests.lsp._client import make_project


def _edit(rng, text):
    (l0, c0), (l1, c1) = rng
    return T.TextDocumentContentChangePartial(
        range=T.Range(T.Position(l0, c0), T.Position(l1, c1)), text=text)


def test_changes_are_applied_with_lsps_line_breaks_and_columns(tmp_path):
    an = Analysis(access=Access(default=tmp_path))
    uri = (tmp_path / "a.plc").as_uri()
    # a form feed and U+2028 are not line breaks for LSP (Python's splitlines says they are)
    an.open(uri, "a\x0cb = 1;\r\n/* \u2028 😀 */ c = 2;\n", 1)
    assert an.docs[uri].text == "a\x0cb = 1;\n/* \u2028 😀 */ c = 2;\n"
    an.change(uri, 2, [_edit(((1, 11), (1, 12)), "dd"), _edit(((0, 0), (0, 1)), "x")])
    assert an.docs[uri].text == "x\x0cb = 1;\n/* \u2028 😀 */ dd = 2;\n"
    an.change(uri, 3, [_edit(((1, 99), (1, 99)), "\r\nq;"), _edit(((9, 0), (9, 0)), "!")])
    assert an.docs[uri].text == "x\x0cb = 1;\n/* \u2028 😀 */ dd = 2;\nq;\n!"
    an.change(uri, 4, [T.TextDocumentContentChangeWholeDocument(text="new")])
    assert an.docs[uri].text == "new" and an.docs[uri].version == 4
    assert not an.change((tmp_path / "closed.plc").as_uri(), 1, [])


def test_which_documents_are_plc(tmp_path):
    root = make_project(tmp_path / "proj")
    an = Analysis(access=Access(default=root))
    toml = (root / "plcbuilder.toml").as_uri()
    an.open(toml, 'name = "t"\n', 1, "toml")
    assert not an.is_plc(toml)
    an.open((root / "include" / "my.h").as_uri(), "#define A 1\n", 1, "c")
    assert an.is_plc((root / "include" / "my.h").as_uri())
    (tmp_path / "c.h").write_text("int f(void);\n")
    an.open((tmp_path / "c.h").as_uri(), "int f(void);\n", 1, "c")
    assert not an.is_plc((tmp_path / "c.h").as_uri())
    an.open((tmp_path / "x.txt").as_uri(), "main() {}\n", 1, "plc")
    assert an.is_plc((tmp_path / "x.txt").as_uri())
    assert an.is_plc((root / "hardware" / "M03.plc").as_uri())
    assert an.check(toml) == {}


def test_reads_stay_inside_the_workspace(tmp_path):
    root = make_project(tmp_path / "proj")
    (tmp_path / "secret.txt").write_text("#define S 1\n")
    (root / "hardware" / "link.plc").symlink_to(tmp_path / "secret.txt")
    an = Analysis(access=Access(default=tmp_path / "elsewhere"))
    an.access.set_folders([root])
    assert an.read(root / "hardware" / "M03.plc") is not None
    assert an.read(tmp_path / "secret.txt") is None
    assert an.read(root / "hardware" / "link.plc") is None            # a link out is outside
    assert an.read(root / "hardware" / ".." / ".." / "secret.txt") is None
    an.open((tmp_path / "secret.txt").as_uri(), "opened", 1)
    assert an.read(tmp_path / "secret.txt") == "opened"               # the client's text


def test_the_incremental_check_gives_what_a_compile_from_scratch_gives(tmp_path):
    root = make_project(tmp_path / "proj")
    an = Analysis(access=Access(default=root))
    path = root / "software" / "S.plc"
    text = "".join(f"p{i}()\n{{\n  v{i} = gvarget({i});\n  gvarset(7000, v{i});\n}};\n"
                   for i in range(40)) + "main() {\n" + "".join(f"  p{i}();\n" for i in range(40)) \
        + "  exit(99);\n};\n"
    path.write_text(text)
    uri = path.as_uri()
    an.open(uri, text, 1)
    an.check(uri)
    edits = [_edit(((52, 0), (52, 0)), "\n"), _edit(((52, 2), (52, 2)), "x"),
             _edit(((10, 0), (10, 0)), "  bad = ;\n"), _edit(((10, 0), (11, 0)), "")]
    opts = an.context(uri).options
    for v, e in enumerate(edits, 2):
        an.change(uri, v, [e])
        got = an.check(uri)[uri]
        want = compile_source(an.docs[uri].text, str(path), opts).diagnostics
        assert [(d.code, d.range.start.line, d.range.start.character) for d in got] == \
               [(d.code, d.span.line - 1, d.span.col - 1) for d in want]
        assert an.results[uri].size == compile_source(an.docs[uri].text, str(path), opts).size
    assert uri in an._incremental
    an.close(uri)
    assert uri not in an._incremental


def test_call_snippets_name_each_argument():
    assert call_snippet("gvarset", ("addr", "value")) == "gvarset(${1:addr}, ${2:value})"
    assert call_snippet("f", ()) == "f()"
    assert call_snippet("g", ("a$b}",)) == "g(${1:a\\$b\\}})"


def test_the_built_in_headers_are_read(tmp_path):
    """The built-in headers are the package's own: read (for the lines of a
    definition there) though they are outside the workspace."""
    from plcbuilder.lsp import features as F
    root = make_project(tmp_path / "proj")
    an = Analysis(access=Access(default=root))
    uri = (root / "hardware" / "M08.plc").as_uri()
    an.open(uri, "main() { portset(OUTPUT_SPINDLE); exit(99); }\n", 1)
    loc = F.definition(an, uri, T.Position(0, 20))
    assert loc.uri.endswith("/resources/include/pins.h")
    text = an.read(uri_path(loc.uri))
    assert text.split("\n")[loc.range.start.line].startswith("#define OUTPUT_SPINDLE")


def test_a_compiler_bug_is_a_diagnostic_not_silence(tmp_path, monkeypatch):
    import plcbuilder.lsp.analysis as analysis

    def broken(*args, **kwargs):
        raise OSError(36, "File name too long")
    monkeypatch.setattr(analysis, "compile_source", broken)
    an = Analysis(access=Access(default=tmp_path))
    uri = (tmp_path / "a.plc").as_uri()
    an.open(uri, "main() { exit(99); }\n", 1)
    got = an.check(uri)[uri]
    assert [d.code for d in got] == ["internal"]
    assert got[0].message == "internal compiler error: OSError: [Errno 36] File name too long"


def test_the_garbage_collector_is_paused_while_a_check_compiles(tmp_path):
    """(Half the time of an Enter at 3,000 lines was the collector going
    through the whole heap in the middle of the compile.)"""
    import gc

    from plcbuilder.lsp.checks import Checks
    an = Analysis(access=Access(default=tmp_path))
    uri = (tmp_path / "a.plc").as_uri()
    an.open(uri, "main() { exit(99); }\n", 1)
    seen = []
    compute = an.compute

    def watched(job):
        seen.append(gc.isenabled())
        return compute(job)
    an.compute = watched
    checks = Checks(an, lambda versions, published: None)
    assert gc.isenabled()
    checks._compute(an.plan(uri))
    assert seen == [False] and gc.isenabled()
