"""Exporting a trace: CSV (one row per change, or per tick) and VCD.

VCD (IEEE 1364 value change dump, written with ``pyvcd``) opens in GTKWave:
timescale 1 ms, one 1-bit ``wire`` per digital signal and an ``integer``
vector per numeric one, as wide as its values need (two's complement when a
value is negative; -2^63 takes 64 bits), scopes by bank (``inputs``,
``outputs``, ``pwm``, ``dac``, ``adc``, ``axes``, ``plc``, ``procedures``,
``variables``). A text signal (``running``) becomes the index of its value in
a ``strings`` comment at the top of the file. libsigrok 0.5 (PulseView,
``sigrok-cli``) reads one-bit signals only: ``split_bits`` writes each number
as that many one-bit lanes ``NAME[0]`` (the lowest bit) … instead.

CSV cells that a spreadsheet would read as a formula (a name starting with
``=``, ``+``, ``-``, ``@``…) are written as OWASP's CSV-injection advice says:
a single quote before them, the cell in double quotes.

Exports are written atomically: a failed export leaves what was there.

Every way of exporting is one row of :data:`EXPORTERS`: its format (the file's
suffix), the option that picks it among its format's ways (``per_tick``,
``split_bits``; none for the format's plain way), the option's command-line
help, the IDE's file-dialog label, and the function that writes it. The
command line (``trace export``, ``run --capture``/``--history``) and the IDE's
File › Export Trace… are made from that table, so a new way of exporting is
one row here (and its test and manual lines).
"""

from __future__ import annotations

import io
import re
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Optional, Union

from plcbuilder._support.files import atomic_write

if TYPE_CHECKING:                      # the writers import it when they run (start-up)
    from plcbuilder.controller.history import Trace

#: a signal's kinds, as controller.history names them (a test holds them equal)
BIT, TEXT = "bit", "text"

#: rows of a per-tick CSV at most (an hour is 3.6 million)
MAX_TICK_ROWS = 10_000_000


class ExportError(Exception):
    """An export that cannot be written; the message names the file and why."""


def _write(path: Path, text: str) -> None:
    try:
        atomic_write(path, text.encode("utf-8"))
    except OSError as exc:
        raise ExportError(f"{path}: cannot write: {exc.strerror or exc}") from None


#: what makes a spreadsheet read a cell as a formula when it starts one (OWASP,
#: "CSV Injection"): = + - @, a tab, a carriage return, and their full-width forms
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r", "\uff1d", "\uff0b", "\uff0d", "\uff20")


def _cell(value) -> str:
    """One CSV cell: a number as it is; a text quoted where CSV needs it, and,
    when it starts as a formula would, as OWASP advises: a single quote before
    it, the whole cell in double quotes (so a spreadsheet shows ``=1+2`` as the
    text ``'=1+2``, never runs it)."""
    if isinstance(value, int):
        return str(value)
    text = str(value)
    formula = text.startswith(_FORMULA_START)
    if formula:
        text = "'" + text
    if formula or any(c in text for c in ',"\r\n'):
        return '"' + text.replace('"', '""') + '"'
    return text


def _row(cells) -> str:
    return ",".join([str(c) if type(c) is int else _cell(c) for c in cells]) + "\n"


def csv_changes(trace: Trace) -> str:
    """``t_ms,signal,value``: one row per change, in time order (a text signal's
    value as its text)."""
    rows = []
    for name, (kind, changes) in trace.signals.items():
        for t, v in changes:
            rows.append((t, name, trace.strings[v] if kind == TEXT else v))
    rows.sort(key=lambda r: r[0])
    return _row(["t_ms", "signal", "value"]) + "".join(map(_row, rows))


def csv_ticks(trace: Trace, t0: Optional[int] = None, t1: Optional[int] = None,
              signals: Optional[list[str]] = None) -> str:
    """One row per tick from t0 to t1 (default the whole trace), a column per
    signal (default every signal that changed at least once), values held
    between changes."""
    t0 = trace.t_start if t0 is None else max(t0, trace.t_start)
    t1 = trace.t_end if t1 is None else min(t1, trace.t_end)
    if t1 - t0 + 1 > MAX_TICK_ROWS:
        raise ExportError(f"{t1 - t0 + 1} ticks is more than {MAX_TICK_ROWS} rows; export "
                          f"per change or a shorter span")
    names = signals if signals is not None else [n for n, (_k, c) in trace.signals.items() if c]
    for n in names:
        if n not in trace.signals:
            raise ExportError(f"no signal named {n!r} in the trace")
    out = io.StringIO()
    out.write(_row(["t_ms", *names]))
    cursors = []
    for n in names:
        kind, ch = trace.signals[n]
        cursors.append([kind, ch, 0, None])
    for t in range(t0, t1 + 1):
        row = [t]
        for cur in cursors:
            kind, ch, i, v = cur
            while i < len(ch) and ch[i][0] <= t:
                v = ch[i][1]
                i += 1
            cur[2], cur[3] = i, v
            row.append("" if v is None else (trace.strings[v] if kind == TEXT else v))
        out.write(_row(row))
    return out.getvalue()


_SCOPES = (("in ", "inputs"), ("out ", "outputs"), ("pwm ", "pwm"), ("dac ", "dac"),
           ("adc ", "adc"), ("axis ", "axes"), ("run ", "procedures"))


def _scope_and_name(signal: str) -> tuple[str, str]:
    for prefix, scope in _SCOPES:
        if signal.startswith(prefix):
            rest = signal[len(prefix):]
            return scope, _ident(f"{prefix.strip()}{rest}" if rest.isdigit() else rest)
    if "." in signal:
        proc, var = signal.split(".", 1)
        return f"variables.{_ident(proc)}", _ident(var)
    return "plc", _ident(signal)


def _ident(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", text) or "_"


def width(kind: str, changes: list) -> int:
    """The bits a signal's values need: 1 for a bit; for a number, its largest
    value's bits, and one more for the sign when a value is negative (two's
    complement), so -2^63 takes 64 bits and 0..1000 takes 10."""
    if kind == BIT or not changes:
        return 1
    values = [v for _t, v in changes]
    lo, hi = min(values), max(values)
    if lo >= 0:
        return max(1, hi.bit_length())
    return max(max(hi, 0).bit_length(), (~lo).bit_length()) + 1


def _comment(text: str) -> str:
    """Text for a VCD ``$comment``: no ``$`` (a ``$end`` would end it), no line breaks."""
    return re.sub(r"[\x00-\x1f\x7f]", " ", text).replace("$", "_")


def vcd_text(trace: Trace, split_bits: bool = False) -> str:
    """The trace as VCD text: each bit signal a 1-bit ``wire``, each number an
    ``integer`` of the width its values need (:func:`width`). ``split_bits``:
    each number as that many 1-bit wires ``NAME[0]`` (the lowest bit) … instead,
    for readers of one-bit signals only (libsigrok 0.5: PulseView, sigrok-cli)."""
    from vcd import VCDWriter

    out = io.StringIO()
    strings = ", ".join(f"{i}={s or '(none)'}" for i, s in enumerate(trace.strings))
    with VCDWriter(out, timescale="1 ms", date="", version="PLC Builder",
                   comment=_comment(f"running: {strings}"), init_timestamp=trace.t_start) as w:
        lanes = []                 # (var, bit or None for the whole value), per signal
        taken: set[tuple[str, str]] = set()
        for name, (kind, changes) in trace.signals.items():
            scope, vname = _scope_and_name(name)
            base, n = vname, 2
            while (scope, vname) in taken:           # two signals one identifier
                vname, n = f"{base}_{n}", n + 1
            taken.add((scope, vname))
            if kind == BIT:
                lanes.append([(w.register_var(scope, vname, "wire", size=1), None)])
                continue
            bits = width(kind, changes)
            if split_bits:
                lanes.append([(w.register_var(scope, f"{vname}[{b}]", "wire", size=1), b)
                              for b in range(bits)])
            else:
                lanes.append([(w.register_var(scope, vname, "integer", size=bits), None)])
        timeline = []
        for k, (kind, changes) in enumerate(trace.signals.values()):
            for t, v in changes:
                timeline.append((t, k, v))
        timeline.sort(key=lambda e: (e[0], e[1]))
        last: dict[int, int] = {}
        for t, k, v in timeline:
            before = last.get(k)
            last[k] = v
            for var, b in lanes[k]:
                if b is None:
                    w.change(var, t, v)
                elif before is None or (before >> b) & 1 != (v >> b) & 1:
                    w.change(var, t, (v >> b) & 1)
        if trace.t_end > (timeline[-1][0] if timeline else trace.t_start):
            w.flush(trace.t_end)
    return out.getvalue()


class Exporter:
    """One way to export a trace (a row of :data:`EXPORTERS`): ``fmt`` the
    format (the file's suffix without the dot), ``option`` the option that
    picks this way (None: the format's plain way), ``label`` the IDE's
    file-dialog label, ``help`` the option's command-line help, ``write`` the
    function that makes the file's text. (A plain class: the command line
    builds its options from these, and a dataclass costs its start-up.)"""

    __slots__ = ("fmt", "option", "label", "help", "write")

    def __init__(self, fmt: str, option: Optional[str], label: str, help: str,
                 write: Callable[["Trace"], str]) -> None:
        self.fmt, self.option, self.label, self.help, self.write = fmt, option, label, help, write

    def __repr__(self) -> str:
        return f"Exporter({self.fmt!r}, {self.option!r})"

    @property
    def flag(self) -> Optional[str]:
        """The command-line flag: ``--per-tick`` for ``per_tick``."""
        return None if self.option is None else "--" + self.option.replace("_", "-")

    @property
    def ide_filter(self) -> str:
        return f"{self.label} (*.{self.fmt})"


#: every way to export, in the order the IDE's file dialog offers them
EXPORTERS: tuple[Exporter, ...] = (
    Exporter("vcd", None, "VCD for GTKWave", "", vcd_text),
    Exporter("vcd", "split_bits", "VCD, one-bit lanes for PulseView and sigrok",
             "VCD: every number as one-bit lanes NAME[0], NAME[1]… (PulseView and "
             "sigrok-cli read only one-bit signals)", lambda t: vcd_text(t, split_bits=True)),
    Exporter("csv", None, "CSV, one row per change", "", csv_changes),
    Exporter("csv", "per_tick", "CSV, one row per tick",
             "CSV: one row per tick and a column per signal (default: one row per change)",
             csv_ticks),
)


def formats() -> list[str]:
    """The formats, in table order: ['vcd', 'csv']."""
    return list(dict.fromkeys(e.fmt for e in EXPORTERS))


def options() -> list[Exporter]:
    """The ways picked by an option (one command-line flag each)."""
    return [e for e in EXPORTERS if e.option is not None]


def can_export(path: Union[str, Path]) -> bool:
    """Whether ``path``'s suffix is an export format."""
    return Path(path).suffix.lower().lstrip(".") in formats()


def exporter(fmt: str, path: Union[str, Path] = "", **chosen: bool) -> Exporter:
    """The way to export ``fmt`` with the options ``chosen`` (those set true);
    raises ExportError naming ``path`` when the format or an option does not fit."""
    picked = [name for name, on in chosen.items() if on]
    known = {e.option for e in options()}
    for name in picked:
        if name not in known:
            raise ExportError(f"{path}: no export option {name!r}")
    if fmt not in formats():
        raise ExportError(f"{path}: export as {' or '.join(sorted(formats()))} (from the "
                          f"file's suffix, or say which)")
    ways = [e for e in EXPORTERS if e.fmt == fmt]
    for name in picked:
        if not any(e.option == name for e in ways):
            other = next(e for e in options() if e.option == name)
            raise ExportError(f"{path}: {other.flag} is for {other.fmt.upper()}, not "
                              f"{fmt.upper()}")
    if len(picked) > 1:
        raise ExportError(f"{path}: choose one of " + ", ".join(
            e.flag for e in ways if e.option in picked))
    return next(e for e in ways if e.option == (picked[0] if picked else None))


def export(trace: "Trace", path: Union[str, Path], fmt: Optional[str] = None,
           **chosen: bool) -> str:
    """Write ``trace`` as ``fmt`` (default from the file's suffix), the way the
    options ``chosen`` pick (``per_tick=True``, ``split_bits=True``: see
    :data:`EXPORTERS`). Returns the format written; raises ExportError."""
    path = Path(path)
    fmt = (fmt or path.suffix.lstrip(".")).lower()
    way = exporter(fmt, path, **chosen)
    _write(path, way.write(trace))
    return fmt
