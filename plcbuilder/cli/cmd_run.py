"""``plcbuilder run TARGET [options] [--json]``: simulate a procedure or a project.

TARGET is a ``.plc`` file (a hardware procedure; ``--software`` for a software
one), started at 0 ms with ``--eparam``, or a project folder, whose software
procedures start by themselves and whose hardware procedures start with
``--start NAME[:EPARAM]@MS``. The run stops at ``--ms`` or when no procedure
runs and none is due to start. Exit status: 0 when the run completed (faults
included), 1 on compile errors, 2 on bad usage.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from plcbuilder.cli import term
from plcbuilder._support.numbers import WORD32
from plcbuilder.cli.common import guarded, int_in, print_diagnostics, safe_streams

#: --gvarget-latency: at most a minute
MAX_LATENCY_MS = 60_000


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "run", help="simulate a procedure or a project on the simulated controller",
        description="Compile TARGET (a .plc file or a project folder) and run it on the "
                    "simulated controller, as fast as it computes. Without --json print a "
                    "summary; with --json one JSON object (procedures, vars, outputs, pwm, "
                    "dac, messages, prints, faults, axes, proc, ended_at_ms).",
        epilog="Scenario lines (--scenario FILE): 'start NAME[:EPARAM] @ MS', "
               "'input PIN=0|1 @ MS', 'adc CH=VALUE @ MS', 'stop @ MS', "
               "'event GCODE_START @ MS', 'bind PIN=NAME[:EPARAM] @ MS', "
               "'write NAME=VALUE @ MS', 'force NAME=VALUE @ MS', "
               "'release NAME|all [keep|restore] @ MS'; '#' starts a "
               "comment. See docs/controller.md, 'Scenario files'.")
    p.add_argument("target", type=Path, metavar="TARGET",
                   help="a .plc file (a hardware procedure) or a project folder")
    p.add_argument("--ms", type=_nonneg, default=None, metavar="N",
                   help="simulated time limit in ms (default 60000); the run also stops when "
                        "no procedure runs and none is due to start")
    p.add_argument("--eparam", type=int_in(*WORD32), default=0, metavar="N",
                   help="the eparam a single-file TARGET starts with (default 0; a 32-bit "
                        "value, -2147483648 to 4294967295, decimal or 0x hex)")
    p.add_argument("--start", action="append", default=[], metavar="NAME[:EPARAM]@MS",
                   help="start a procedure at MS (repeatable)")
    p.add_argument("--input", action="append", default=[], metavar="PIN=0|1@MS",
                   help="set an input by hand at MS (repeatable; overrides the machine's "
                        "wiring of that pin from then on)")
    p.add_argument("--adc", action="append", default=[], metavar="CH=VALUE@MS",
                   help="set an ADC channel by hand at MS (repeatable)")
    p.add_argument("--write", action="append", default=[], metavar="NAME=VALUE@MS",
                   help="set a value once at MS (repeatable); NAME is PROC.var, 'in N', "
                        "'out N', 'adc N', 'pwm N', 'dac N' or 'gvar N'")
    p.add_argument("--force", action="append", default=[], metavar="NAME=VALUE@MS",
                   help="hold a value from MS on (repeatable; names as --write): reads see "
                        "it and the program's writes are discarded")
    p.add_argument("--scenario", type=Path, metavar="FILE",
                   help="a scenario file: one start/input/adc/stop/event line each")
    p.add_argument("--machine", type=Path, metavar="FILE",
                   help="the machine description (TOML; default: the project's, else the "
                        "built-in default machine)")
    p.add_argument("--software", action="store_true",
                   help="run a single file as a software procedure")
    p.add_argument("--strict", action="store_true",
                   help="compile in controller compatibility mode")
    p.add_argument("-I", "--include", dest="include", action="append", default=[], type=Path,
                   metavar="DIR", help="search DIR for #include files (repeatable)")
    p.add_argument("--trace", type=Path, metavar="FILE.csv",
                   help="write one CSV row per tick (streamed; gzip if it ends in .gz)")
    g = p.add_argument_group("traces and triggers (docs/traces.md)")
    g.add_argument("--trigger", metavar="SPEC",
                   help="capture around the first time SPEC happens: 'out 7 rise', "
                        "'in 3 fall', 'adc 0 up 1200', 'proc = 33', 'message', 'print = 20001', "
                        "'M80.var03 bit 2 rise' (needs --capture)")
    g.add_argument("--pre", type=_nonneg, default=0, metavar="MS",
                   help="ms kept before the trigger (default 0)")
    g.add_argument("--post", type=_nonneg, default=0, metavar="MS",
                   help="ms kept after the trigger (default 0)")
    g.add_argument("--trigger-mode", choices=("single", "normal", "auto"), default="single",
                   help="single: one capture; normal: re-arm after each (FILE-2, FILE-3, …); "
                        "auto: also capture when no trigger came for pre+post ms")
    g.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the capture: .plctrace (reopens in the IDE), or by its suffix "
                        "any format `plcbuilder trace export` writes")
    g.add_argument("--history", type=Path, metavar="FILE",
                   help="write the whole session as a trace: .plctrace, or by its suffix any "
                        "format `plcbuilder trace export` writes")
    g.add_argument("--watch", action="append", default=[], metavar="PROC.var",
                   help="record a variable every tick into the history (repeatable)")
    p.add_argument("--break", dest="breaks", action="append", default=[],
                   metavar="FILE:LINE[:COND]",
                   help="halt before FILE's line LINE runs (or the next line with code), "
                        "when COND (a PLC expression) is not 0; the run ends there and the "
                        "JSON's 'halted' says where (repeatable; docs/debugging.md)")
    p.add_argument("--gcode", type=Path, metavar="FILE",
                   help="run a G-code program as a job from 0 ms: G0/G1/G4/G28/G90/G91, S, "
                        "Mnn starts procedure Mnn and waits for its exit or its "
                        "PLCCMD_MOTION_CONTINUE; the JSON gains 'job' (docs/controller.md)")
    p.add_argument("--scope", action="append", default=[], metavar="SIGNAL",
                   help="TG Motion: a signal the oscilloscope samples after each Program_04 "
                        "(repeatable; 'in 9', 'out 7', 'adc 0', 'gvar 2000001', "
                        "'Program.x'; default: the project's [tgmotion] oscilloscope)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--state", type=Path, metavar="FILE",
                   help="the controller's kept state (Huazhong's B registers): read from FILE "
                        "before the run when it exists, written to it after")
    p.add_argument("--backend", choices=("fast", "reference"), default="fast",
                   help=argparse.SUPPRESS)
    p.add_argument("--gvarget-latency", type=int_in(0, MAX_LATENCY_MS, "ms"), default=0,
                   metavar="MS",
                   help="host round-trip latency of gvarget of plain registers (default 0)")
    term.add_color_argument(p)
    return p


def _int(text: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None


def _nonneg(text: str) -> int:
    v = _int(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"must not be negative: {text!r}")
    return v


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        from plcbuilder import api
        target: Path = args.target
        opts = api.RunOptions(ms=args.ms, eparam=args.eparam, starts=args.start, inputs=args.input,
                          adcs=args.adc, writes=args.write, forces=args.force,
                          scenario=args.scenario, machine=args.machine,
                          software=args.software, strict=args.strict, include_dirs=tuple(args.include),
                          trace=args.trace, backend=args.backend,
                          gvarget_latency_ms=args.gvarget_latency, trigger=args.trigger,
                          pre_ms=args.pre, post_ms=args.post, trigger_mode=args.trigger_mode,
                          capture=args.capture, history=args.history, watch=tuple(args.watch),
                          state=args.state, breaks=args.breaks, scope=tuple(args.scope),
                          gcode=args.gcode)
        try:
            result = api.run(target, opts)
        except api.UsageError as exc:
            out.print(f"plcbuilder run: error: {exc}", err=True)
            return 2
        for r in result.compiled:
            if r.diagnostics and (not result.ok or not args.json):
                print_diagnostics(r, out, err=True)
        if not result.ok:
            bad = [r.name for r in result.compiled if not r.ok]
            out.print(f"plcbuilder run: not run: {', '.join(bad)} did not compile", err=True)
            return 1
        if args.json:
            import json
            out.print(json.dumps(result.report))
        else:
            out.print(summary(result.report, out))
        return 0

    return guarded(body, out)


def summary(rep: dict, out: term.Out) -> str:
    """A readable account of a run report."""
    lines = []
    for p in rep["procedures"]:
        head = f"{p['name']} ({p['kind']})"
        if p["eparam"]:
            head += f" eparam {p['eparam']}"
        if p["ended_at_ms"] is None:
            lines.append(f"{head}: started at {p['started_at_ms']} ms, still running")
        else:
            code = p["exit_code"]
            name = f" {p['exit_name']}" if p["exit_name"] else (" (fault)" if code == -1 else "")
            lines.append(f"{head}: {p['started_at_ms']} -> {p['ended_at_ms']} ms, exit {code}"
                         f"{name}, vexit {p['vexit']}")
    if not rep["procedures"]:
        lines.append("no procedure ran")
    for f in rep["faults"]:
        where = f"{f['file']}:{f['line']}: " if f["file"] else ""
        lines.append(out.paint("bad", f"fault at {f['t_ms']} ms in {f['from']}: {where}{f['text']}"))
    if rep["messages"]:
        lines.append("messages:")
        for m in rep["messages"]:
            name = f" {m['name']}" if m["name"] else ""
            lines.append(f"  {m['t_ms']:>7} ms  {m['from']}: {m['message']}{name} "
                         f"(command {m['command']}, parameter {m['parameter']})")
    if rep["prints"]:
        lines.append("prints:")
        for p in rep["prints"]:
            lines.append(f"  {p['t_ms']:>7} ms  {p['from']}: [{p['register']}] {p['value']}")
    if rep.get("logs"):                 # logpoints, and TG Motion's RtWprintf_* prints
        lines.append("log:")
        for entry in rep["logs"][:50]:
            lines.append(f"  {entry['t_ms']:>7} ms  {entry['from']}: {entry['text']}")
        if len(rep["logs"]) > 50:
            lines.append(f"  ... {len(rep['logs']) - 50} more (all of them in --json's logs)")
    notes = [n for n in rep["notes"] if n["level"] != "info"]
    for n in notes[:50]:
        lines.append(f"{n['level']} at {n['t_ms']} ms: {n['text']}")
    if len(notes) > 50:
        lines.append(f"... {len(notes) - 50} more warnings")
    lines.append("outputs on: " + (", ".join(map(str, rep["outputs"])) or "none"))
    for key, what in (("vins", "virtual inputs"), ("vouts", "virtual outputs")):
        if rep.get(key):
            lines.append(f"{what} on: " + ", ".join(map(str, rep[key])))
    for p in rep.get("pls") or ():                     # softMC's PLSs (docs/targets.md)
        lines.append(f"PLS{p['pls']} {p['name']}: {p['axis'] or '-'} -> {p['output'] or '-'}, "
                     f"{'enabled' if p['enabled'] else 'disabled'}, output {p['state']}")
    for key in ("pwm", "dac"):
        if any(rep[key]):
            lines.append(f"{key}: " + " ".join(map(str, rep[key])))
    if rep["axes"]:
        lines.append("axes: " + "  ".join(f"{a} {v / 100:.2f}" for a, v in rep["axes"].items()))
    proc = rep["proc"]
    lines.append(f"proc: {proc}" + (f" ({rep['proc_name']})" if rep.get("proc_name") else ""))
    for name, variables in rep["vars"].items():
        own = {k: v for k, v in variables.items()
               if not (k.startswith("var") and k[3:].isdigit()) or v}
        lines.append(f"{name}: " + ", ".join(f"{k}={v}" for k, v in own.items()))
    if rep.get("forces"):
        lines.append("forced: " + ", ".join(f"{f['target']}={f['value']} (from {f['since_ms']} ms)"
                                            for f in rep["forces"]))
    job = rep.get("job")
    if job:
        end = f" at {job['ended_at_ms']} ms" if job["ended_at_ms"] is not None else ""
        lines.append(f"job {job['file']}: {job['state']}{end}, line {job['line']} of "
                     f"{job['lines']}" + (f": {job['error']}" if job["error"] else ""))
        for m in job["mcodes"]:
            ended = (f"{m['ended_at_ms']} ms, exit {m['exit_code']}"
                     + (f" {m['exit_name']}" if m["exit_name"] else "")
                     if m["ended_at_ms"] is not None else "still running")
            cont = (f", continued at {m['continued_at_ms']} ms"
                    if m["continued_at_ms"] is not None else "")
            lines.append(f"  line {m['line']}: {m['code']} -> {m['procedure'] or '(none)'} "
                         f"{m['started_at_ms']} -> {ended}{cont}")
    if "registers" in rep:
        for bank, vals in rep["registers"].items():
            if vals:
                lines.append(f"{bank}: " + " ".join(f"[{i}]={v}" for i, v in vals.items()))
        lines.append("calls: " + ", ".join(f"{n} {k}" for n, k in rep["calls"].items()))
    osc = rep.get("oscilloscope")
    if osc:                                            # TG Motion's (docs/targets.md)
        head = f"oscilloscope: {osc['samples']} samples of {', '.join(osc['signals'])}"
        if osc["last"]:
            t_us, cycle, *values = osc["last"][-1]
            head += (f"; the last at {t_us} us (cycle {cycle}): "
                     + " ".join(map(str, values)))
        lines.append(head)
    if "capture" in rep:
        cap = rep["capture"]
        lines.append("capture: " + (f"triggered at {cap['t_ms']} ms, {cap['from_ms']}.."
                                    f"{cap['to_ms']} ms -> {', '.join(cap['files'])}"
                                    if cap else "the trigger never fired; nothing written"))
    if rep.get("history"):
        lines.append(f"history: {rep['history']['file']}")
    still = [p["name"] for p in rep["procedures"] if p["ended_at_ms"] is None]
    why = "time limit" if still else "nothing left to run"
    h = rep.get("halted")
    if h is not None:
        where = " <- ".join(f"{f['procedure']}() line {f['line']}" for f in h["stack"])
        lines.append(out.paint("bad", f"halted ({h['reason']}) at {h['t_ms']} ms in "
                                      f"{h['procedure']}: {h['file']}:{h['line']}"
                                      + (f" [{where}]" if where else "")))
        why = "halted"
    lines.append(f"run ended at {rep['ended_at_ms']} ms ({why})")
    return "\n".join(lines)
