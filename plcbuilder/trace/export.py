"""Exporting a trace: CSV (one row per change, or per tick) and VCD.

VCD (IEEE 1364 value change dump, written with ``pyvcd``) opens in GTKWave and
PulseView: timescale 1 ms, one 1-bit ``wire`` per digital signal and a 32-bit
``integer`` vector per numeric one (two's complement), scopes by bank
(``inputs``, ``outputs``, ``pwm``, ``dac``, ``adc``, ``axes``, ``plc``,
``procedures``, ``variables``). A text signal (``running``) becomes the index
of its value in a ``strings`` comment at the top of the file.

Exports are written atomically: a failed export leaves what was there.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path
from typing import Optional, Union

from vcd import VCDWriter

from plcbuilder._support.files import atomic_write
from plcbuilder.controller.history import BIT, TEXT, Trace

#: rows of a per-tick CSV at most (an hour is 3.6 million)
MAX_TICK_ROWS = 10_000_000


class ExportError(Exception):
    """An export that cannot be written; the message names the file and why."""


def _write(path: Path, text: str) -> None:
    try:
        atomic_write(path, text.encode("utf-8"))
    except OSError as exc:
        raise ExportError(f"{path}: cannot write: {exc.strerror or exc}") from None


def csv_changes(trace: Trace) -> str:
    """``t_ms,signal,value``: one row per change, in time order (a text signal's
    value as its text), then the events as ``t_ms,event,<type>: …`` rows."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["t_ms", "signal", "value"])
    rows = []
    for name, (kind, changes) in trace.signals.items():
        for t, v in changes:
            rows.append((t, name, trace.strings[v] if kind == TEXT else v))
    rows.sort(key=lambda r: r[0])
    w.writerows(rows)
    return out.getvalue()


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
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["t_ms", *names])
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
        w.writerow(row)
    return out.getvalue()


_SCOPES = (("in ", "inputs"), ("out ", "outputs"), ("pwm ", "pwm"), ("dac ", "dac"),
           ("adc ", "adc"), ("axis ", "axes"), ("run ", "procedures"))


def _scope_and_name(signal: str) -> tuple[str, str]:
    for prefix, scope in _SCOPES:
        if signal.startswith(prefix):
            rest = signal[len(prefix):]
            return scope, (f"{prefix.strip()}{rest}" if rest.isdigit() else rest)
    if "." in signal:
        proc, var = signal.split(".", 1)
        return f"variables.{_ident(proc)}", _ident(var)
    return "plc", _ident(signal)


def _ident(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", text) or "_"


def vcd_text(trace: Trace) -> str:
    """The trace as VCD text."""
    out = io.StringIO()
    strings = ", ".join(f"{i}={s or '(none)'}" for i, s in enumerate(trace.strings))
    with VCDWriter(out, timescale="1 ms", date="", version="PLC Builder",
                   comment=f"running: {strings}", init_timestamp=trace.t_start) as w:
        variables = []
        for name, (kind, changes) in trace.signals.items():
            scope, vname = _scope_and_name(name)
            if kind == BIT:
                var = w.register_var(scope, vname, "wire", size=1)
            else:
                var = w.register_var(scope, vname, "integer", size=32)
            variables.append((var, kind, changes))
        timeline = []
        for k, (var, kind, changes) in enumerate(variables):
            for t, v in changes:
                timeline.append((t, k, v))
        timeline.sort(key=lambda e: (e[0], e[1]))
        for t, k, v in timeline:
            var, kind, _ = variables[k]
            if kind != BIT:
                v &= 0xFFFFFFFF
            w.change(var, t, v)
        if trace.t_end > (timeline[-1][0] if timeline else trace.t_start):
            w.flush(trace.t_end)
    return out.getvalue()


def export(trace: Trace, path: Union[str, Path], fmt: Optional[str] = None, *,
           per_tick: bool = False) -> str:
    """Write ``trace`` as ``fmt`` ('csv' or 'vcd'; default from the file's suffix).
    Returns the format written; raises ExportError."""
    path = Path(path)
    fmt = (fmt or path.suffix.lstrip(".")).lower()
    if fmt == "vcd":
        _write(path, vcd_text(trace))
    elif fmt == "csv":
        _write(path, csv_ticks(trace) if per_tick else csv_changes(trace))
    else:
        raise ExportError(f"{path}: export as csv or vcd (from the file's suffix, or say which)")
    return fmt
