"""Issue 28.6: a diagnostic's one serialisation lives with the type
(DESIGN.md: ``diagnostics.py`` ... to/from dict), not in Build All."""

import json

import pytest

from plcbuilder.diagnostics import Diagnostic, Related, Severity, Span, error, warning


def _sample() -> list[Diagnostic]:
    at = Span("hardware/M03.plc", 3, 5, 4, 2)
    return [
        error("undeclared", "'x' is not declared", at, "did you mean 'y'?",
              related=[Related(Span.point("include/pins.h", 7, 1), "'y' is declared here")]),
        warning("unused-variable", "'t' is set but never read", Span.point("p.plc", 1, 1)),
        Diagnostic(Severity.NOTE, "note", "a note without a place", None),
    ]


def test_to_dict_is_json_and_from_dict_reads_it_back():
    for d in _sample():
        v = d.to_dict()
        assert json.loads(json.dumps(v)) == v
        assert Diagnostic.from_dict(json.loads(json.dumps(v))) == d
        Diagnostic.check_dict(v)


def test_the_dict_has_the_documented_shape():
    v = _sample()[0].to_dict()
    assert v == {"severity": 1, "code": "undeclared", "message": "'x' is not declared",
                 "span": ["hardware/M03.plc", 3, 5, 4, 2], "hints": ["did you mean 'y'?"],
                 "related": [[["include/pins.h", 7, 1, 7, 2], "'y' is declared here"]]}


@pytest.mark.parametrize("bad", [
    None, [], {}, {"severity": 9, "code": "c", "message": "m", "span": None, "hints": [],
                   "related": []},
    {"severity": 1, "code": 3, "message": "m", "span": None, "hints": [], "related": []},
    {"severity": 1, "code": "c", "message": "m", "span": ["f", 1, 2], "hints": [],
     "related": []},
    {"severity": 1, "code": "c", "message": "m", "span": None, "hints": [1], "related": []},
    {"severity": 1, "code": "c", "message": "m", "span": None, "hints": [],
     "related": [[None]]},
    {"severity": 1, "code": "c", "message": "m", "span": None, "hints": [],
     "related": [[["f", 1, "2", 1, 3], "m"]]},
])
def test_a_malformed_dict_is_a_value_error(bad):
    with pytest.raises(ValueError):
        Diagnostic.check_dict(bad)
    with pytest.raises(ValueError):
        Diagnostic.from_dict(bad)
