"""Every golden program compiles (or fails) exactly as its inline expectations say."""

import pytest

from tests.lang.golden_util import compile_golden, goldens, listing

GOLDENS = goldens()


@pytest.mark.parametrize("g", GOLDENS, ids=[g.id for g in GOLDENS])
def test_diagnostics(g):
    r = compile_golden(g)
    main = str(g.path)
    actual = [d for d in r.diagnostics if d.span is None or d.span.file == main]
    unmatched = list(actual)
    for line, sev, text in g.diags:
        hits = [d for d in unmatched if d.span and d.span.line == line and d.severity.label == sev
                and (text in d.message or any(text in h for h in d.hints))]
        assert hits, f"{g.id}:{line}: expected {sev} containing {text!r}; got " + \
            "; ".join(f"{d.span.line if d.span else '-'}: {d.severity.label}: {d.message}" for d in actual)
        assert len(hits) == 1, f"{g.id}:{line}: {sev} {text!r} reported {len(hits)} times"
        unmatched.remove(hits[0])
    assert not unmatched, f"{g.id}: unexpected diagnostics: " + \
        "; ".join(f"{d.span.line if d.span else '-'}: {d.severity.label}: {d.message}" for d in unmatched)
    expects_error = any(sev == "error" for _, sev, _ in g.diags)
    assert (r.program is None) == expects_error
    if r.program is not None:
        assert r.size <= r.limit


@pytest.mark.parametrize("g", [g for g in GOLDENS if not any(s == "error" for _, s, _ in g.diags)],
                         ids=lambda g: g.id)
def test_disassembly_golden(g):
    r = compile_golden(g)
    assert g.dis_path.exists(), f"{g.dis_path.name} is missing: run scripts/regen_goldens.py"
    assert listing(g, r) == g.dis_path.read_text(encoding="utf-8"), \
        f"{g.id}: the code changed; if that is intended, run scripts/regen_goldens.py"


@pytest.mark.parametrize("g", [g for g in GOLDENS if not any(s == "error" for _, s, _ in g.diags)],
                         ids=lambda g: g.id)
def test_deterministic(g):
    a = compile_golden(g).program.to_bytes()
    b = compile_golden(g).program.to_bytes()
    assert a == b
