"""The editor widget: text and positions, highlighting, editing helpers,
find/replace, diagnostics as indicators and markers, hover, completion."""

import pytest
from PySide6.QtCore import Qt

from plcbuilder.diagnostics import Span, error, warning
from plcbuilder.ide import highlighter as hl
from plcbuilder.ide.editor import (IND_ERROR, IND_FIND, IND_WARNING, MK_ERROR, MK_WARNING,
                                   CodeEditor, EditorPrefs, normalise_newlines)
from plcbuilder.ide.offsets import utf8_len

SRC = ("// héllo wörld\n"
       "#include pins.h\n"
       "main() {\n"
       "    a = gvarget(6060);\n"
       "    /* ünïcode\n"
       "       still comment */ b = 1;\n"
       "    exit(99);\n"
       "}\n")


@pytest.fixture
def ed(qtbot):
    e = CodeEditor()
    qtbot.addWidget(e)
    e.resize(700, 400)
    e.show()
    qtbot.waitExposed(e)
    return e


def test_text_round_trip_and_positions(ed):
    ed.set_text(SRC)
    assert ed.text() == SRC
    assert ed.length() == utf8_len(SRC)
    # line 1 col 5 is 'é' (after "// h"); its byte position is 4
    assert ed.position_of(1, 5) == 4
    assert ed.line_col_of(4) == (1, 5)
    # 'w' of wörld: chars "// héllo " = 9 chars, 10 bytes
    assert ed.position_of(1, 10) == 10
    assert ed.line_col_of(ed.position_of(5, 8)) == (5, 8)
    # past the end of a line clamps to the line end; past the last line to the end
    assert ed.position_of(2, 999) == ed.lineEndPosition(1)
    assert ed.position_of(999, 1) == ed.length()


def test_highlighting_styles_every_byte(ed):
    ed.set_text(SRC)
    ed.highlighter.style_to(ed.length())
    assert ed.endStyled() == ed.length()
    style_at = lambda line, col: ed.styleAt(ed.position_of(line, col))  # noqa: E731
    assert style_at(1, 5) == hl.S_COMMENT            # inside the non-ASCII comment
    assert style_at(2, 1) == hl.S_PREPROC
    assert style_at(3, 1) == hl.S_FUNCTION
    assert style_at(4, 9) == hl.S_BUILTIN            # gvarget
    assert style_at(4, 17) == hl.S_NUMBER            # 6060
    assert style_at(6, 8) == hl.S_COMMENT            # second line of /* */
    assert style_at(6, 25) == hl.S_IDENT             # b, after the comment closed
    assert style_at(7, 5) == hl.S_BUILTIN            # exit


def test_incremental_restyle_follows_an_opened_comment(ed):
    ed.set_text("a = 1;\nb = 2;\nc = 3;\n")
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(3, 1)) == hl.S_IDENT
    ed.insertText(0, "/* ")
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(3, 1)) == hl.S_COMMENT
    ed.insertText(ed.position_of(2, 1), "*/ ")
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(3, 1)) == hl.S_IDENT


def test_defines_get_their_style(ed):
    ed.set_text("main() { portset(OUTPUT_SPINDLE); }\n")
    ed.highlighter.set_defines({"OUTPUT_SPINDLE"})
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(1, 18)) == hl.S_DEFINE


def test_folding_levels(ed):
    ed.set_text("main() {\n  if (a) {\n    b = 1;\n  } else {\n    b = 2;\n  }\n}\n")
    ed.highlighter.style_to(ed.length())
    assert ed.foldLevel(0) & hl.FOLD_HEADER
    assert ed.foldLevel(1) & hl.FOLD_HEADER
    assert ed.foldLevel(3) & hl.FOLD_HEADER           # } else {
    assert not ed.foldLevel(2) & hl.FOLD_HEADER
    ed.foldLine(0, 0)                                 # contract main
    assert not ed.lineVisible(3)
    ed.foldLine(0, 1)
    assert ed.lineVisible(3)


def test_typing_auto_indents_and_dedents(ed, qtbot):
    ed.take_focus()
    qtbot.keyClicks(ed, "main() {")
    qtbot.keyClick(ed, Qt.Key.Key_Return)
    qtbot.keyClicks(ed, "a = 1;")
    qtbot.keyClick(ed, Qt.Key.Key_Return)
    qtbot.keyClicks(ed, "}")
    assert ed.text() == "main() {\n    a = 1;\n}"


def test_enter_between_braces_opens_a_block(ed, qtbot):
    ed.set_text("main() {}")
    ed.gotoPos(8)
    ed.take_focus()
    qtbot.keyClick(ed, Qt.Key.Key_Return)
    assert ed.text() == "main() {\n    \n}"
    assert ed.cursor_line_col() == (2, 5)


def test_brace_matching(ed):
    ed.set_text("main() { a = (1); }")
    ed.highlighter.style_to(ed.length())
    ed.gotoPos(7)                 # before {
    ed._match_braces()
    assert ed.braceMatch(7, 0) == 18


def test_toggle_comment(ed):
    ed.set_text("main() {\n    a = 1;\n\n    b = 2;\n}\n")
    ed.setSel(ed.position_of(2, 1), ed.position_of(4, 3))
    ed.toggle_comment()
    assert ed.text() == "main() {\n    // a = 1;\n\n    // b = 2;\n}\n"
    ed.setSel(ed.position_of(2, 1), ed.position_of(4, 3))
    ed.toggle_comment()
    assert ed.text() == "main() {\n    a = 1;\n\n    b = 2;\n}\n"
    ed.gotoPos(0)
    ed.toggle_comment()
    assert ed.line_text(0) == "// main() {"
    ed.undo()
    assert ed.line_text(0) == "main() {"


def test_find_replace_with_non_ascii(ed):
    ed.set_text("é = 1; é = 2;\nx = é;\n")
    assert ed.find("é")
    assert ed.selected_text() == "é"
    assert ed.line_col_of(ed.selectionStart()) == (1, 1)
    assert ed.find("é")
    assert ed.line_col_of(ed.selectionStart()) == (1, 8)
    assert ed.find("é", forward=False)
    assert ed.line_col_of(ed.selectionStart()) == (1, 1)
    assert ed.highlight_matches("é") == 3
    assert len(ed.indicator_ranges(IND_FIND)) == 3
    assert not ed.find("nothing")
    assert ed.replace_all("é", "ü") == 3
    assert ed.text() == "ü = 1; ü = 2;\nx = ü;\n"
    ed.undo()                                     # replace all is one step
    assert ed.text() == "é = 1; é = 2;\nx = é;\n"
    ed.gotoPos(0)
    ed.find("é")
    ed.replace("é", "zz")
    assert ed.text().startswith("zz = 1; é")
    assert ed.selected_text() == "é"              # moved on to the next match


def test_find_flags(ed):
    ed.set_text("Alpha alpha alphabet\n")
    flags = CodeEditor.search_flags(case=True, whole=True)
    assert ed.highlight_matches("alpha", flags) == 1
    assert ed.highlight_matches("alpha", CodeEditor.search_flags()) == 3
    assert ed.highlight_matches("al[a-z]+", CodeEditor.search_flags(regex=True)) == 3


def test_diagnostics_become_indicators_and_markers(ed):
    ed.set_text("// ünï\nmain() { x = ; }\ny é = 2;\n")
    diags = [error("syntax", "expected an expression", Span("<f>", 2, 14, 2, 15)),
             warning("unused", "é is never read", Span("<f>", 3, 3, 3, 4))]
    ed.set_diagnostics(diags)
    err = ed.indicator_ranges(IND_ERROR)
    assert err == [(ed.position_of(2, 14), ed.position_of(2, 15))]
    warn = ed.indicator_ranges(IND_WARNING)
    start = ed.position_of(3, 3)
    assert warn == [(start, start + 2)]            # é is two bytes
    assert ed.diagnostic_lines() == {2: MK_ERROR, 3: MK_WARNING}
    assert "expected an expression" in ed.hover_text_at(ed.position_of(2, 14))
    ed.set_diagnostics([])
    assert ed.indicator_ranges(IND_ERROR) == []
    assert ed.diagnostic_lines() == {}


def test_point_diagnostic_at_line_end_is_visible(ed):
    ed.set_text("main() { a = 1\n}\n")
    ed.set_diagnostics([error("syntax", "expected ';'", Span("<f>", 1, 15, 1, 15))])
    (s, e), = ed.indicator_ranges(IND_ERROR)
    assert e > s


def test_hover_and_signature_providers(ed):
    ed.set_text("main() { a = gvarget(6060); }\n")
    ed.hover_provider = lambda e, pos: f"word {e.word_at(pos)[2]}"
    assert ed.hover_text_at(ed.position_of(1, 23)) == "word 6060"
    ed.apply_prefs(EditorPrefs(hover=False))
    assert ed.hover_text_at(ed.position_of(1, 23)) is None


def test_completion_list_opens_while_typing(ed, qtbot):
    ed.completion_provider = lambda e, prefix: [("gvarget", 1), ("gvarset", 1), ("a", 2)]
    ed.take_focus()
    qtbot.keyClicks(ed, "x = gv")
    assert ed.autoCActive()
    ed.autoCCancel()
    ed.set_text("// gv")
    ed.gotoPos(ed.length())
    qtbot.keyClicks(ed, "a")                      # in a comment: no list
    assert not ed.autoCActive()


def test_call_tip_on_open_paren(ed, qtbot):
    ed.signature_provider = lambda name: "portset(pin)" if name == "portset" else None
    ed.take_focus()
    qtbot.keyClicks(ed, "portset(")
    assert ed.callTipActive()
    qtbot.keyClicks(ed, "1)")
    assert not ed.callTipActive()


def test_goto_line_and_prefs(ed):
    ed.set_text("\n".join(f"line{i}" for i in range(200)))
    ed.goto_line(150, 3)
    assert ed.cursor_line_col() == (150, 3)
    ed.apply_prefs(EditorPrefs(font_size=14, tab_width=2, theme="dark", show_whitespace=True))
    assert ed.tabWidth() == 2
    assert ed.viewWS() == 1
    assert ed.styleBack(hl.STYLE_DEFAULT) == hl.colour(hl.DARK.paper)


def test_normalise_newlines():
    assert normalise_newlines("a\r\nb\r\n") == ("a\nb\n", "\r\n")
    assert normalise_newlines("a\nb") == ("a\nb", "\n")
    assert normalise_newlines("a\rb") == ("a\nb", "\n")


def test_settings_and_xml_files_get_their_own_highlighting(ed):
    from plcbuilder.ide.highlighter import lexer_for
    assert lexer_for("a/M03.plc") is None and lexer_for("pins.h") is None
    assert lexer_for("notes.txt") is False
    ed.highlighter.set_lexer(lexer_for("plcbuilder.toml"))
    ed.set_text('name = "é x"   # a comment\n[limits]\nhw_proc = 512\n')
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(1, 9)) == hl.S_STRING
    assert ed.styleAt(ed.position_of(1, 18)) == hl.S_COMMENT
    assert ed.styleAt(ed.position_of(3, 11)) == hl.S_NUMBER
    ed.highlighter.set_lexer(lexer_for("plc-variables.xml"))
    ed.set_text('<vars><!-- c --><var name="var00" value="1"/></vars>\n')
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(0) == hl.S_TAG
    assert ed.styleAt(ed.position_of(1, 8)) == hl.S_COMMENT
