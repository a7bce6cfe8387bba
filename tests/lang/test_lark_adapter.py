"""Issue 28.7 and 26.1: what the parser needs of lark is behind one module,
``lang/lark_adapter.py``, which builds the parse tables once; the tables are
checked in (``lang/grammar_tables.py``) and must be what lark builds from
``grammar.lark``; a command parses without importing lark."""

import subprocess
import sys

import pytest

from plcbuilder.lang import grammar_tables, lalr, lark_adapter
from plcbuilder.lang.parser import AstBuilder, parse_tokens
from plcbuilder.lang.preprocess import Preprocessor

REGENERATE = ("run `.venv/bin/python -m plcbuilder.lang.lark_adapter` and commit "
              "plcbuilder/lang/grammar_tables.py")


def test_the_checked_in_tables_are_what_lark_builds_from_the_grammar():
    assert grammar_tables.GRAMMAR == lark_adapter.grammar_text(), \
        f"grammar.lark changed since its tables were built: {REGENERATE}"
    built = lark_adapter.build_tables()        # raises LarkChanged, saying what, after an upgrade
    assert built == lark_adapter.tables_of_module(grammar_tables), \
        f"lark builds other tables from grammar.lark than grammar_tables.py holds: {REGENERATE}"


def test_building_is_deterministic():
    a = lark_adapter.tables_source(lark_adapter.build_tables())
    assert a == lark_adapter.tables_source(lark_adapter.build_tables())


def _odd_lark(monkeypatch, change):
    """lark.Lark as a later lark might build it: ``change(parser)`` after."""
    import lark
    real = lark.Lark

    class Odd(real):
        def __init__(self, *a, **k):
            super().__init__(*a, **k)
            change(self)
    monkeypatch.setattr(lark, "Lark", Odd)


def test_a_changed_parse_action_is_named_in_a_sentence(monkeypatch):
    def actions_as_strings(parser):
        states = parser.parser.parser.parser.parse_table.states
        for row in states.values():
            for sym, (action, arg) in list(row.items()):
                row[sym] = (str(action).lower(), arg)
    _odd_lark(monkeypatch, actions_as_strings)
    with pytest.raises(lark_adapter.LarkChanged) as info:
        lark_adapter.build_tables()
    msg = str(info.value)
    assert msg.startswith("lark 1.") and "neither (Shift, state) nor (Reduce, one of Lark.rules)" \
        in msg and "lark_adapter.py" in msg


def test_a_missing_parse_table_is_named(monkeypatch):
    def no_table(parser):
        del parser.parser.parser.parser.parse_table
    _odd_lark(monkeypatch, no_table)
    with pytest.raises(lark_adapter.LarkChanged, match="parse_table is gone"):
        lark_adapter.build_tables()


def test_a_changed_parse_table_shape_is_named(monkeypatch):
    def other_start(parser):
        parser.parser.parser.parser.parse_table.start_states = {"begin": 0}
    _odd_lark(monkeypatch, other_start)
    with pytest.raises(lark_adapter.LarkChanged, match="start symbol 'start'"):
        lark_adapter.build_tables()


def test_every_rule_has_its_tree_builder_method():
    t = lalr.tables()
    for origin, size, method, expand1, children in t.rules:
        if method is None:
            assert origin.startswith("__"), origin          # a helper list (x*)
        elif not (expand1 and size == 1 and children is None):
            assert callable(getattr(AstBuilder, method, None)), f"AstBuilder.{method} is missing"


def test_stale_tables_are_rebuilt_from_the_grammar(monkeypatch):
    """An edited grammar.lark whose tables were not regenerated still parses
    right (lark builds them then), never with the old tables."""
    monkeypatch.setattr(grammar_tables, "GRAMMAR", "// an older grammar")
    data = lalr._load()
    assert data["grammar"] == lark_adapter.grammar_text()      # built by lark just now
    assert len(data["states"]) == len(grammar_tables.STATES)


def test_a_command_parses_without_lark():
    code = ("import sys\n"
            "from plcbuilder.lang.pipeline import compile_source\n"
            "r = compile_source('main(){ x = (1 + ; exit(99); };', 'M.plc')\n"
            "assert [d.code for d in r.diagnostics if d.is_error] == ['syntax'], r.diagnostics\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('lark', 'dataclasses')))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]", r.stdout


def test_the_parse_is_lark_s():
    """The parser's loop over the tables gives the tree lark's own parser
    gives (the fuzz tests compare many more programs)."""
    import lark
    text = ("main()\n{\n  a = 1 + 2 * -(3 << b[1]) || !c;\n  if (a) { f(); } else do x++; "
            "while (a != 2);\n  gvarset(7, a & 3, b);\n};\nf(){ ; }\n")
    toks = Preprocessor(()).run_text(text, "M.plc", None).tokens
    ours, diags = parse_tokens(toks)
    assert not diags
    theirs = lark.Lark(lark_adapter.grammar_text(), parser="lalr").parse(text)
    procs = [c for c in theirs.children if c.data == "proc_def"]
    assert len(ours.procs) == len(procs) == 2
    assert [p.name for p in ours.procs] == [str(c.children[0]) for c in procs]
    assert len(ours.procs[0].body.stmts) == 3
