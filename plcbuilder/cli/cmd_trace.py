"""``plcbuilder trace info|export|compare``: trace files from the command line.

    trace info FILE                  the span, the signals and how often each changed
    trace export FILE OUT [--format F] [the format's options]
                                     (the formats: trace.export.EXPORTERS)
    trace compare A B [--align none|start|trigger] [--offset MS] [--json]
                                     the first tick where they differ (exit 1), or 0
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from plcbuilder.cli import term
from plcbuilder.cli.common import guarded, int_in, safe_streams


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser("trace", help="show, export or compare trace files",
                              description="Trace files (.plctrace) from `run --capture`, "
                                          "`run --history` or the IDE: see docs/traces.md.")
    sub = p.add_subparsers(dest="trace_command", metavar="ACTION", required=True)
    i = sub.add_parser("info", help="the span, signals and changes of a trace file")
    i.add_argument("file", type=Path, metavar="FILE")
    i.add_argument("--json", action="store_true", help="print one JSON object")
    from plcbuilder import api
    ways = api.trace_exporters()
    formats = list(dict.fromkeys(w.fmt for w in ways))
    e = sub.add_parser("export", help="export a trace file as "
                                      + " or ".join(f.upper() for f in formats))
    e.add_argument("file", type=Path, metavar="FILE")
    e.add_argument("out", type=Path, metavar="OUT",
                   help=" or ".join(f"OUT.{f}" for f in formats))
    e.add_argument("--format", choices=formats, help="default: from OUT's suffix")
    for w in ways:
        if w.option is not None:
            e.add_argument(w.flag, dest=w.option, action="store_true", help=w.help)
    c = sub.add_parser("compare", help="the first tick where two traces differ")
    c.add_argument("a", type=Path, metavar="A")
    c.add_argument("b", type=Path, metavar="B")
    c.add_argument("--align", choices=("none", "start", "trigger"), default="none",
                   help="line B up with A before comparing: none (the same times, the "
                        "default), start (the two starts together) or trigger (the two "
                        "captures' triggers together)")
    c.add_argument("--offset", type=int_in(-(1 << 53), 1 << 53), default=0, metavar="MS",
                   help="then move B by MS more (may be negative)")
    c.add_argument("--json", action="store_true", help="print one JSON object")
    for q in (i, e, c):
        term.add_color_argument(q)
    return p


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        from plcbuilder import api
        try:
            if args.trace_command == "compare":
                a, b = api.load_trace(args.a), api.load_trace(args.b)
                diff = api.compare_traces(a, b, args.align, args.offset)
                out.print(json.dumps(diff.to_dict()) if args.json else diff.text())
                return 0 if diff.same else 1
            trace = api.load_trace(args.file)
            if args.trace_command == "export":
                fmt = api.export_trace(trace, args.out, args.format, **{
                    w.option: getattr(args, w.option) for w in api.trace_exporters()
                    if w.option is not None})
                out.print(f"wrote {args.out} ({fmt})")
                return 0
            changed = {n: len(ch) for n, (_k, ch) in trace.signals.items()}
            if args.json:
                out.print(json.dumps({"t_start": trace.t_start, "t_end": trace.t_end,
                                      "meta": trace.meta, "events": len(trace.events),
                                      "signals": [{"name": n, "kind": trace.signals[n][0],
                                                   "changes": k} for n, k in changed.items()]}))
                return 0
            out.print(f"{args.file}: {trace.t_start}..{trace.t_end} ms, {len(changed)} signals, "
                      f"{len(trace.events)} events")
            trig = trace.meta.get("trigger")
            if trig:
                out.print(f"trigger: {trig['spec']} at {trig['t_ms']} ms")
            for n, k in changed.items():
                if k > 1:
                    out.print(f"  {n}: {k} changes")
            return 0
        except (api.TraceFileError, api.ExportError, api.CompareError) as exc:
            out.print(f"plcbuilder trace: error: {exc}", err=True)
            return 2

    return guarded(body, out)
