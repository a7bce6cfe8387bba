"""The one place that knows lark's insides: it turns ``grammar.lark`` into the
parse tables the parser runs on (``grammar_tables.py``).

lark builds LALR(1) tables well, but building them takes a quarter of a
second and importing lark alone costs more than a whole ``plcbuilder check``
of a small file may take. So the tables are built once, here, and checked in
as package data; :mod:`plcbuilder.lang.lalr` reads them and the parser
(:mod:`plcbuilder.lang.parser`) drives them without importing lark: the
tables are a Python module of literals, which Python keeps compiled, so reading
them costs next to nothing. A test
(``tests/lang/test_lark_adapter.py``) builds them again and fails, saying
what to do, when they differ from the file or when a lark upgrade changed one
of the things below.

What is read from lark (each checked, with a sentence when it is not so):

- ``Lark.parser.parser.parser.parse_table``: the LALR table of the front end's
  parser (states numbered 0..N-1; per state, symbol -> (Shift, state) or
  (Reduce, rule)); ``start_states``/``end_states`` keyed by the start symbol.
- ``Lark.rules``: each rule's origin, expansion (symbols with ``is_term``,
  ``filter_out``), ``alias`` and ``options.expand1``/``keep_all_tokens``.
- How lark shapes values as it reduces (``parse_tree_builder``): a rule's
  value is its callback's (the alias or the rule's name, a method of the tree
  builder) on its children; a nonterminal whose name starts with ``_`` is
  spliced into its parent's children (the helper rules of ``x*`` are named
  ``__start_star_0`` and so on); a terminal marked ``filter_out`` is dropped; a
  ``?rule`` (``expand1``) without an alias gives its only child itself.

Regenerate after changing the grammar::

    .venv/bin/python -m plcbuilder.lang.lark_adapter
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

GRAMMAR = Path(__file__).with_name("grammar.lark")
TABLES = Path(__file__).with_name("grammar_tables.py")
FORMAT = 1
START = "start"


class LarkChanged(Exception):
    """lark no longer looks the way this module reads it (after an upgrade)."""


def grammar_text() -> str:
    return GRAMMAR.read_text(encoding="utf-8")


def grammar_digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _expect(ok: bool, what: str) -> None:
    if not ok:
        import lark
        raise LarkChanged(f"lark {lark.__version__}: {what}; plcbuilder/lang/lark_adapter.py "
                          "reads lark's parse table and rules and needs updating for it")


def build_tables(text: str | None = None) -> dict:
    """The parse tables of the grammar (``grammar.lark`` unless ``text``), as
    the dict of plain values :mod:`plcbuilder.lang.lalr` reads."""
    import lark
    from lark.parsers import lalr_analysis

    text = grammar_text() if text is None else text
    parser = lark.Lark(text, parser="lalr", lexer="basic", maybe_placeholders=False)
    front = getattr(parser, "parser", None)
    lalr = getattr(getattr(front, "parser", None), "parser", None)
    table = getattr(lalr, "parse_table", None)
    _expect(table is not None, "Lark(...).parser.parser.parser.parse_table is gone")
    for name in ("states", "start_states", "end_states"):
        _expect(hasattr(table, name), f"the parse table has no '{name}'")
    _expect(START in table.start_states and START in table.end_states,
            f"the parse table's start_states/end_states are not keyed by the start symbol "
            f"'{START}'")
    states = table.states
    _expect(sorted(states) == list(range(len(states))),
            "the parse table's states are not numbered 0..N-1 (IntParseTable)")
    shift = getattr(lalr_analysis, "Shift", None)
    reduce = getattr(lalr_analysis, "Reduce", None)
    _expect(shift is not None and reduce is not None,
            "lark.parsers.lalr_analysis has no Shift/Reduce actions")

    rules = list(parser.rules)
    index = {id(r): i for i, r in enumerate(rules)}
    out_rules = []
    for r in rules:
        for attr in ("origin", "expansion", "alias", "options"):
            _expect(hasattr(r, attr), f"a Rule has no '{attr}'")
        _expect(hasattr(r.options, "expand1") and hasattr(r.options, "keep_all_tokens"),
                "RuleOptions has no expand1/keep_all_tokens")
        keep_all = bool(r.options.keep_all_tokens)
        spec = []
        plain = True
        for i, sym in enumerate(r.expansion):
            _expect(hasattr(sym, "is_term") and hasattr(sym, "name"),
                    "a rule's symbol has no is_term/name")
            if sym.is_term and getattr(sym, "filter_out", False) and not keep_all:
                plain = False
                continue
            splice = not sym.is_term and sym.name.startswith("_")
            plain = plain and not splice
            spec.append([i, 1 if splice else 0])
        origin = r.origin.name
        helper = origin.startswith("_")
        method = None if helper else str(r.alias or origin)
        expand1 = bool(r.options.expand1) and not r.alias and not helper
        out_rules.append([origin, len(r.expansion), method, expand1, None if plain else spec])

    # lark numbers states in an order that changes from run to run (sets of
    # items, hash-seeded): number them in the order a breadth-first walk from
    # the start state meets them, symbols in sorted order, so the file is the
    # same every time
    for row in states.values():
        for action, arg in row.values():
            _expect((action is shift and arg in states) or (action is reduce and id(arg) in index),
                    "a parse action is neither (Shift, state) nor (Reduce, one of Lark.rules)")
    start_state = table.start_states[START]
    order = [start_state]
    number = {start_state: 0}
    for s in order:
        for sym in sorted(states[s]):
            action, arg = states[s][sym]
            if action is shift and arg not in number:
                number[arg] = len(order)
                order.append(arg)
    _expect(len(order) == len(states), "some parse states cannot be reached from the start state")
    out_states = []
    for s in order:
        row = {}
        for sym, (action, arg) in states[s].items():
            if action is shift:
                row[sym] = number[arg]
            else:
                row[sym] = -1 - index[id(arg)]
        out_states.append(row)

    start_rules = [r for r in rules if r.origin.name == START and r.expansion]
    _expect(len(start_rules) == 1 and len(start_rules[0].expansion) == 1
            and start_rules[0].expansion[0].name.startswith("__"),
            f"'{START}: item*' is no longer one rule over a helper list rule (it was "
            f"'__start_star_0')")
    list_symbol = start_rules[0].expansion[0].name
    _expect(isinstance(states[start_state].get(list_symbol), tuple),
            f"the start state has no goto on the item list '{list_symbol}'")
    list_state = number[states[start_state][list_symbol][1]]
    return {"format": FORMAT, "grammar_sha256": grammar_digest(text), "grammar": text,
            "lark": lark.__version__, "start_state": 0,
            "end_state": number[table.end_states[START]], "list_symbol": list_symbol,
            "list_state": list_state, "rules": out_rules, "states": out_states}


def tables_source(tables: dict) -> str:
    """The module's text: one rule and one state a line (diffs stay readable)."""
    lines = ['"""The LALR(1) tables of grammar.lark, built by lark: generated by',
             "``python -m plcbuilder.lang.lark_adapter``; do not edit (see lark_adapter.py).",
             '"""', "", "# flake8: noqa", ""]
    for k, v in tables.items():
        if k in ("rules", "states"):
            continue
        lines.append(f"{k.upper()} = {v!r}")
    lines.append("RULES = [")
    lines += [f"    {json.dumps(r, separators=(',', ':')).replace('null', 'None').replace('true', 'True').replace('false', 'False')},"
              for r in tables["rules"]]
    lines.append("]")
    lines.append("STATES = [")
    lines += [f"    {json.dumps(st, separators=(',', ':'), sort_keys=True)}," for st in tables["states"]]
    lines.append("]")
    return "\n".join(lines) + "\n"


def tables_of_module(module) -> dict:
    """The dict :func:`build_tables` makes, from the generated module."""
    out = {k.lower(): getattr(module, k) for k in dir(module) if k.isupper()}
    return out


def main() -> int:
    TABLES.write_text(tables_source(build_tables()), encoding="utf-8")
    print(f"wrote {TABLES}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
