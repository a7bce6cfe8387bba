"""``plcbuilder test PROJECT [-k TEXT] [--junit FILE] [--json] [--coverage]
[--coverage-xml FILE]``:
run the project's scenario tests (``tests/*.toml``, SPEC §8).

Builds the project (writing nothing), runs every test on the simulated
controller and prints one line per test (a failing one with its failing
condition, expected and actual, and the tick; more failing conditions on the
lines below), then ``N passed, N failed``. A test file that cannot be read
is reported (its file, line and reason) and its tests left out; the others
run. Exit status 0 when all pass, 1 when any fails (or the project does not
build), 2 for bad usage or a test file that cannot be read.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from plcbuilder.cli import term
from plcbuilder.cli.common import guarded, int_in, print_diagnostics, safe_streams


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "test", help="run a project's scenario tests (tests/*.toml)",
        description="Build PROJECT and run its scenario tests (tests/*.toml) on the "
                    "simulated controller. One line per test, then 'N passed, N failed'. "
                    "Exit status 0 when all pass, 1 when any fails, 2 for bad usage or a "
                    "test file that cannot be read.")
    p.add_argument("project", type=Path, metavar="PROJECT", nargs="?", default=Path("."),
                   help="the project folder (default: the current folder)")
    p.add_argument("-k", dest="select", metavar="TEXT",
                   help="run only the tests whose name (or file name) contains TEXT "
                        "(ignoring case)")
    p.add_argument("--junit", type=Path, metavar="FILE", help="write JUnit XML to FILE")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--coverage", action="store_true",
                   help="report per procedure which source lines ran and which ways its "
                        "conditions went, then a TOTAL line (runs on the reference "
                        "interpreter)")
    p.add_argument("--coverage-xml", type=Path, metavar="FILE",
                   help="write the coverage as Cobertura XML to FILE (as pytest-cov's "
                        "--cov-report xml; GitLab and Jenkins read it)")
    p.add_argument("--trace-failed", type=Path, metavar="DIR",
                   help="write each failing test's run as a CSV trace in DIR (one row a "
                        "tick, as 'plcbuilder run --trace')")
    p.add_argument("-j", "--jobs", type=int_in(1, 256), default=None, metavar="N",
                   help="processes to run tests in (default: the cores, when the tests "
                        "are many)")
    term.add_color_argument(p)
    return p


def run(args: argparse.Namespace) -> int:
    safe_streams()
    out = term.Out(args.color)

    def body() -> int:
        from plcbuilder import api
        opts = api.TestOptions(select=args.select,
                               coverage=args.coverage or args.coverage_xml is not None,
                               jobs=args.jobs, trace_dir=args.trace_failed)
        try:
            tr = api.test(args.project, opts)
        except api.UsageError as exc:
            out.print(f"plcbuilder test: error: {exc}", err=True)
            return 2
        for e in tr.errors:
            out.print(out.paint("error", f"{e}", err=True), err=True)
        if not tr.built:
            for pb in tr.compiled:
                if any(d.is_error for d in pb.diagnostics):
                    print_diagnostics(pb, out, err=True)
            bad = [pb.name for pb in tr.compiled if not pb.ok]
            out.print(f"plcbuilder test: not run: {', '.join(bad)} did not compile", err=True)
        if args.junit is not None and (tr.run is not None or tr.errors):
            try:
                api.write_junit(args.junit, tr.suite.project.name or "tests", tr.results,
                                tr.errors)
            except OSError as exc:
                out.print(f"plcbuilder test: error: cannot write {args.junit}: "
                          f"{exc.strerror or exc}", err=True)
                return 2
        if args.coverage_xml is not None and tr.run is not None \
                and tr.run.coverage is not None:
            try:
                api.write_cobertura(args.coverage_xml, tr.run.coverage, tr.suite.project.root)
            except OSError as exc:
                out.print(f"plcbuilder test: error: cannot write {args.coverage_xml}: "
                          f"{exc.strerror or exc}", err=True)
                return 2
        if args.json:
            out.print(json.dumps(tr.to_dict()))
            return tr.exit_status
        if tr.run is None:
            return tr.exit_status
        for r in tr.results:
            out.print(result_line(r, out))
        if tr.run.coverage is not None and args.coverage:
            out.print(coverage_text(tr.run.coverage, tr.suite.project.root))
        if not tr.results and not tr.errors:
            out.print(f"no tests in {tr.suite.project.root / 'tests'}"
                      + (f" matching {args.select!r}" if args.select else ""))
        out.print(f"{tr.run.passed} passed, {tr.run.failed} failed")
        if tr.errors:
            n = len(tr.errors)
            out.print(f"plcbuilder test: {n} mistake{'s' if n > 1 else ''} in test files "
                      f"(above): those tests did not run", err=True)
        return tr.exit_status

    return guarded(body, out)


def result_line(r, out: term.Out) -> str:
    """``PASS  name`` or ``FAIL  name: FILE:LINE: when: condition: expected …, actual …
    at tick T``, more failing conditions indented below."""
    if r.passed:
        return f"{out.paint('ok', 'PASS')}  {r.name}"
    head = f"{out.paint('bad', 'FAIL')}  {r.name}: "
    if r.error is not None:
        return head + f"{r.file}:{r.line}: could not run: {r.error}"
    lines = [head + r.failures[0].text()]
    lines += ["      " + f.text() for f in r.failures[1:]]
    if r.trace:
        lines.append(f"      trace: {r.trace}")
    return "\n".join(lines)


def coverage_text(coverage, root=None) -> str:
    """Per procedure: its percentage, lines run of lines with code, the ways
    its conditions went of the ways they have, the uncovered lines; then
    ``TOTAL`` over every source file (a header several procedures include
    counted once), the line a CI coverage regex reads."""
    from plcbuilder import api
    lines = ["coverage (lines with code that ran; measured on the reference interpreter):"]
    width = max([len(c.name) for c in coverage] + [len("TOTAL")])
    for c in coverage:
        text = f"  {c.name.ljust(width)}  {c.percent:5.1f}%  {c.covered}/{c.lines} lines"
        if c.branches:
            text += f"  {c.branches_covered}/{c.branches} branches"
        missing = c.uncovered_text()
        if missing:
            text += f"  not run: {missing}"
        lines.append(text)
    n, ran, ways, gone = api.coverage_totals(coverage, root)
    percent = 100.0 * ran / n if n else 100.0
    lines.append(f"  {'TOTAL'.ljust(width)}  {percent:5.1f}%  {ran}/{n} lines  "
                 f"{gone}/{ways} branches")
    return "\n".join(lines)
