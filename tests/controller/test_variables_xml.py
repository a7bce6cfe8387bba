"""plc-variables.xml: var00..var15, decimal and hex, refused with file and line."""

from __future__ import annotations

import pytest

from plcbuilder.controller.machine_config import ConfigError
from plcbuilder.controller.variables_xml import load_variables, parse_variables


def test_variables_decimal_and_hex(tmp_path):
    """var00..var15 are initialised from plc-variables.xml (decimal and 0x hex)."""
    p = tmp_path / "plc-variables.xml"
    p.write_text('<?xml version="1.0" encoding="UTF-8"?>\n<plc-variables>\n'
                 '  <!-- a comment -->\n'
                 '  <var name="var00" value="5"/>\n'
                 '  <var name="var03" value="0x10"/>\n'
                 '  <var name="var15" value="-7"/>\n'
                 '  <var name="var14" value="0xFFFFFFFF"/>\n'
                 '</plc-variables>\n', encoding="utf-8")
    v = load_variables(p)
    assert len(v) == 16
    assert v[0] == 5 and v[3] == 16 and v[15] == -7 and v[14] == -1
    assert v[1] == 0 and v[13] == 0


def test_empty_variables_file():
    assert parse_variables(b"<plc-variables/>") == [0] * 16


@pytest.mark.parametrize("body,line,words", [
    ('<plc-variables>\n<var name="var00" value="5"/>\n<var name="var16" value="1"/>\n'
     '</plc-variables>', 3, "var16"),
    ('<plc-variables>\n\n<var name="var01" value="five"/>\n</plc-variables>', 3, "five"),
    ('<plc-variables>\n<var name="var01" value="1"/>\n<var name="var01" value="2"/>\n'
     '</plc-variables>', 3, "twice"),
    ('<plc-variables>\n<var name="var01" value="99999999999"/>\n</plc-variables>', 2, "32 bits"),
    ('<plc-variables>\n<var name="var01"/>\n</plc-variables>', 2, "needs both"),
    ('<plc-variables>\n<variable name="var01" value="1"/>\n</plc-variables>', 2, "unexpected"),
    ('<vars>\n</vars>', 1, "root"),
    ('<plc-variables>\n<var name="var01" value="1">\n</plc-variables>', 3, "syntax"),
])
def test_bad_variables_file_names_file_and_line(tmp_path, body, line, words):
    """A bad plc-variables.xml raises ConfigError whose message names the file and line."""
    p = tmp_path / "plc-variables.xml"
    p.write_text(body, encoding="utf-8")
    with pytest.raises(ConfigError) as ei:
        load_variables(p)
    e = ei.value
    assert e.file == str(p) and e.line == line, str(e)
    assert str(e).startswith(f"{p}:{line}: ") and words in str(e)


def test_xml_bomb_is_refused(tmp_path):
    """An XML bomb must be refused with a clear error."""
    bomb = ('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
            ' <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">\n'
            ' <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">\n]>\n'
            '<plc-variables><var name="var00" value="&lol3;"/></plc-variables>\n')
    p = tmp_path / "plc-variables.xml"
    p.write_text(bomb, encoding="utf-8")
    with pytest.raises(ConfigError) as ei:
        load_variables(p)
    assert "refused" in str(ei.value) and "XML bomb" in str(ei.value)
    assert str(p) in str(ei.value)


def test_external_entity_is_refused(tmp_path):
    """An external entity must be refused with a clear error (nothing is read)."""
    secret = tmp_path / "secret.txt"
    secret.write_text("42")
    xml = (f'<?xml version="1.0"?>\n<!DOCTYPE v [ <!ENTITY x SYSTEM "file://{secret}"> ]>\n'
           '<plc-variables><var name="var00" value="&x;"/></plc-variables>\n')
    with pytest.raises(ConfigError) as ei:
        parse_variables(xml, "v.xml")
    assert "refused" in str(ei.value) and "external" in str(ei.value)
    # a DOCTYPE with an external DTD is refused as well
    xml = ('<?xml version="1.0"?>\n<!DOCTYPE plc-variables SYSTEM "http://example.invalid/x.dtd">\n'
           '<plc-variables/>\n')
    with pytest.raises(ConfigError) as ei:
        parse_variables(xml, "v.xml")
    assert "refused" in str(ei.value)


def test_missing_variables_file(tmp_path):
    with pytest.raises(ConfigError) as ei:
        load_variables(tmp_path / "nope.xml")
    assert "nope.xml" in str(ei.value)
