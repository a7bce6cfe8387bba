"""Terminal output for the command line: whether to colour, and how.

Colour is decided once per command from ``--color=auto|always|never``:
``always`` and ``never`` are obeyed as given; ``auto`` colours only a terminal
(``isatty``), and never when ``NO_COLOR`` is set to anything non-empty
(https://no-color.org) or ``TERM`` is ``dumb``.

:func:`colorize` is the ``colorize(kind, text)`` hook of
:func:`plcbuilder.diagnostics.render_text`; source lines (kind ``"source"``)
are highlighted with the PLC pygments lexer.
"""

from __future__ import annotations

import argparse
import functools
import os
import sys

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Optional, TextIO

COLOR_CHOICES = ("auto", "always", "never")

_RESET = "\x1b[0m"
#: SGR codes per kind of text (kinds of diagnostics.render_text, plus a few of ours).
STYLES: dict[str, str] = {
    "location": "1",        # bold
    "error": "1;31",        # bold red
    "warning": "1;35",      # bold magenta
    "note": "1;36",         # bold cyan
    "caret": "1;32",        # bold green
    "hint": "36",           # cyan
    "ok": "32",             # green
    "bad": "31",            # red
    "dim": "2",             # faint: addresses, line numbers
    "heading": "1",         # bold
}


def add_color_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--color=auto|always|never`` (also spelled ``--colour``)."""
    parser.add_argument("--color", "--colour", dest="color", choices=COLOR_CHOICES,
                        default="auto", metavar="WHEN",
                        help="colour the output: auto (default: on a terminal, unless NO_COLOR "
                             "is set), always or never")


def want_color(mode: str = "auto", stream: Optional[TextIO] = None,
               environ: Optional[dict] = None) -> bool:
    """Whether output written to ``stream`` (default stdout) should be coloured."""
    if mode == "always":
        return True
    if mode == "never":
        return False
    env = os.environ if environ is None else environ
    if env.get("NO_COLOR"):
        return False
    if env.get("TERM") == "dumb":
        return False
    stream = sys.stdout if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


def paint(kind: str, text: str) -> str:
    """Wrap text in the SGR colour of its kind (text of an unknown kind is returned as is)."""
    code = STYLES.get(kind)
    if not code or not text:
        return text
    return f"\x1b[{code}m{text}{_RESET}"


@functools.lru_cache(maxsize=1)
def _highlighter():
    from pygments.formatters import TerminalFormatter
    from plcbuilder.api import PlcLexer
    return PlcLexer(ensurenl=False), TerminalFormatter()


def highlight(text: str) -> str:
    """PLC source text in terminal colours (line breaks and all other text kept as they are)."""
    if not text:
        return text
    try:
        from pygments import format as pyg_format
        lexer, formatter = _highlighter()
        tokens = ((tok, value) for _pos, tok, value in lexer.get_tokens_unprocessed(text))
        return pyg_format(tokens, formatter)
    except Exception:  # colouring must never break a command
        return text


def colorize(kind: str, text: str) -> str:
    """The ``colorize`` hook of ``diagnostics.render_text``: source lines are
    highlighted, every other kind is painted in its style."""
    if kind == "source":
        return highlight(text)
    return paint(kind, text)


def colorizer(enabled: bool) -> Optional[Callable[[str, str], str]]:
    """``colorize`` when colour is on, else None (render_text then prints plain text)."""
    return colorize if enabled else None


class Out:
    """One command's output: stdout and stderr, each with its own colour decision."""

    def __init__(self, mode: str = "auto", stdout: Optional[TextIO] = None,
                 stderr: Optional[TextIO] = None):
        self.stdout = sys.stdout if stdout is None else stdout
        self.stderr = sys.stderr if stderr is None else stderr
        self.color = want_color(mode, self.stdout)
        self.color_err = want_color(mode, self.stderr)

    def paint(self, kind: str, text: str, err: bool = False) -> str:
        return paint(kind, text) if (self.color_err if err else self.color) else text

    def colorize(self, err: bool = False) -> Optional[Callable[[str, str], str]]:
        return colorizer(self.color_err if err else self.color)

    def highlight(self, text: str) -> str:
        return highlight(text) if self.color else text

    def print(self, text: str = "", err: bool = False) -> None:
        stream = self.stderr if err else self.stdout
        stream.write(text + "\n")
