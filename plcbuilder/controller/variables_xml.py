"""``plc-variables.xml``: the initial values of var00..var15 (docs/machine.md).

Read with defusedxml: a DTD, an entity declaration (an XML bomb) or an external
entity is refused. Problems raise :class:`ConfigError` naming the file and line.
"""

from __future__ import annotations

import re
from pathlib import Path

from plcbuilder._support.files import read_bounded
from plcbuilder.bytecode.semantics import wrap

from .machine_config import ConfigError

VARIABLE_COUNT = 16
_VARIABLES_MAX_BYTES = 1 << 20

_NUMBER = re.compile(r"^\s*(-?)(0[xX][0-9a-fA-F]+|[0-9]+)\s*$")


def parse_int_value(text: str) -> int:
    """A decimal or 0x-hex integer (optionally negative) as a signed 32-bit value.

    Raises ValueError for anything else or for a value that does not fit 32 bits
    (-2147483648 .. 4294967295; hex above 0x7fffffff wraps, as in C).
    """
    m = _NUMBER.match(text)
    if not m:
        raise ValueError(f"{text!r} is not a decimal or 0x-hex integer")
    v = int(m.group(2), 0) if not re.fullmatch(r"0[0-9]+", m.group(2)) else int(m.group(2), 10)
    if m.group(1):
        v = -v
    if v < -(1 << 31) or v > 0xFFFFFFFF:
        raise ValueError(f"{text.strip()} does not fit in 32 bits")
    return wrap(v)


def load_variables(path) -> list[int]:
    """Read ``plc-variables.xml``: the initial values of var00..var15.

    The format (docs/machine.md)::

        <plc-variables>
          <var name="var00" value="5"/>
          <var name="var03" value="0x10"/>
        </plc-variables>

    Variables not listed are 0. Raises :class:`ConfigError` naming the file and
    line for a bad file; a DTD, entity declaration (XML bomb) or external
    entity is refused.
    """
    p = Path(path)
    try:
        data = read_bounded(p, _VARIABLES_MAX_BYTES, "variables file")
    except OSError as e:
        raise ConfigError(f"cannot read the variables file: {e.strerror or e}", str(p)) from None
    return parse_variables(data, str(p))


def parse_variables(data: bytes | str, name: str = "plc-variables.xml") -> list[int]:
    """Parse the text of a plc-variables.xml (see :func:`load_variables`)."""
    import xml.sax
    import xml.sax.handler

    import defusedxml
    import defusedxml.sax

    if isinstance(data, str):
        data = data.encode("utf-8")
    if len(data) > _VARIABLES_MAX_BYTES:
        raise ConfigError(f"the file is too large ({len(data)} bytes; at most "
                          f"{_VARIABLES_MAX_BYTES})", name)
    values = [0] * VARIABLE_COUNT
    seen: dict[int, int] = {}

    class Handler(xml.sax.handler.ContentHandler):
        def __init__(self):
            super().__init__()
            self.locator = None
            self.depth = 0

        def setDocumentLocator(self, locator):
            self.locator = locator

        def line(self):
            return self.locator.getLineNumber() if self.locator else None

        def fail(self, msg, key=None):
            raise ConfigError(msg, name, self.line(), key)

        def startElement(self, tag, attrs):
            self.depth += 1
            if self.depth == 1:
                if tag != "plc-variables":
                    self.fail(f"the root element must be <plc-variables>, not <{tag}>")
                if attrs.getNames():
                    self.fail(f"<plc-variables> takes no attributes "
                              f"(found {', '.join(attrs.getNames())})")
                return
            if self.depth > 2 or tag != "var":
                self.fail(f"unexpected element <{tag}> (expected <var name=\"varNN\" value=\"N\"/>)")
            names = set(attrs.getNames())
            extra = names - {"name", "value"}
            if extra:
                self.fail(f"<var> has unknown attribute(s) {', '.join(sorted(extra))}")
            if "name" not in names or "value" not in names:
                self.fail("<var> needs both name=\"varNN\" and value=\"N\"")
            vname = attrs.getValue("name").strip()
            m = re.fullmatch(r"var(\d\d)", vname)
            if not m or int(m.group(1)) >= VARIABLE_COUNT:
                self.fail(f"unknown variable {vname!r} (var00..var15)", vname or "name")
            idx = int(m.group(1))
            if idx in seen:
                self.fail(f"{vname} is given twice (first on line {seen[idx]})", vname)
            try:
                values[idx] = parse_int_value(attrs.getValue("value"))
            except ValueError as e:
                self.fail(str(e), vname)
            seen[idx] = self.line()

        def endElement(self, tag):
            self.depth -= 1

        def characters(self, content):
            if content.strip():
                self.fail(f"unexpected text {content.strip()[:20]!r}")

    handler = Handler()
    try:
        defusedxml.sax.parseString(data, handler, forbid_dtd=True, forbid_entities=True,
                                   forbid_external=True)
    except ConfigError:
        raise
    except defusedxml.DefusedXmlException as e:
        raise ConfigError(
            f"refused: the file contains a DTD, entity declaration or external reference "
            f"({type(e).__name__}); plc-variables.xml must be plain XML (this protects "
            f"against XML bombs and external entities)", name, handler.line()) from None
    except xml.sax.SAXParseException as e:
        raise ConfigError(f"XML syntax error: {e.getMessage()}", name, e.getLineNumber()) from None
    return values
