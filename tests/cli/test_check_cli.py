"""``plcbuilder check``, the options the compiling commands share, and terminal colour."""

from __future__ import annotations

import glob
import io
import re
import subprocess
import sys
from pathlib import Path

import pytest

from plcbuilder.cli import term
from plcbuilder.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
ANSI = re.compile(r"\x1b\[[0-9;]*m")

GOOD = """main()
{
  portset(1);
  timer=10; do{timer--;}while(timer>0);
  exit(99);
};
"""
BAD = """main()
{
  code=gvarset(6060);
  exit(code);
};
"""
WARN_ONLY = """main()
{
  portset(1);
};
"""


@pytest.fixture
def work(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("NO_COLOR", raising=False)
    return tmp_path


def write(folder: Path, name: str, text: str | bytes) -> Path:
    p = folder / name
    p.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return p


def check(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["check", *argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


# ------------------------------------------------------------ output and exit status

def test_clean_file_exits_0_with_size_summary(work, capsys):
    write(work, "M03.plc", GOOD)
    rc, out, err = check(capsys, "M03.plc")
    assert rc == 0, out + err
    assert out.splitlines() == [
        re.match(r"M03\.plc: ok: 0 errors, 0 warnings; hardware procedure M03, \d+/512 bytes",
                 out.strip()).group()]
    assert "\x1b[" not in out, "no colour when stdout is not a terminal"


def test_error_is_located_with_source_line_caret_and_hint(work, capsys):
    write(work, "M05.plc", BAD)
    rc, out, _err = check(capsys, "M05.plc")
    assert rc == 1
    lines = out.splitlines()
    i = lines.index("M05.plc:3:8: error: gvarset takes 2 arguments and returns nothing; "
                    "did you mean gvarget(6060)?")
    assert lines[i + 1] == "      code=gvarset(6060);"
    assert lines[i + 2] == "           ^~~~~~~~~~~~~"
    assert lines[i + 3].startswith("  hint: ")
    assert lines[-1].startswith("M05.plc: failed: 1 error, ")
    assert lines[-1].endswith("not compiled (limit 512 bytes)")


def test_warnings_alone_do_not_fail(work, capsys):
    write(work, "M07.plc", WARN_ONLY)
    rc, out, _err = check(capsys, "M07.plc")
    assert rc == 0
    assert re.search(r"^M07\.plc:4:1: warning: main\(\) can reach its end without exit\(\)", out, re.M)
    assert "M07.plc: ok: 0 errors, 1 warning;" in out


def test_several_files_each_get_a_summary_and_any_error_fails(work, capsys):
    write(work, "A.plc", GOOD)
    write(work, "B.plc", BAD)
    write(work, "C.plc", GOOD)
    rc, out, _err = check(capsys, "A.plc", "B.plc", "C.plc")
    assert rc == 1
    summaries = [line.split(":")[0] for line in out.splitlines()
                 if re.match(r"^[ABC]\.plc: (ok|failed):", line)]
    assert summaries == ["A.plc", "B.plc", "C.plc"]


def test_missing_file_is_a_diagnostic_on_that_file(work, capsys):
    write(work, "A.plc", GOOD)
    rc, out, err = check(capsys, "A.plc", "nothere.plc")
    assert rc == 1
    assert "nothere.plc:1:1: error: nothere.plc: no such file" in out
    assert "A.plc: ok" in out
    assert "Traceback" not in out + err


@pytest.mark.parametrize("content", [b"\x00\x01PLCB\x00" * 10, b"\xff\xfe\x00m\x00a"])
def test_binary_file_is_a_diagnostic(work, capsys, content):
    write(work, "X.plc", content)
    rc, out, err = check(capsys, "X.plc")
    assert rc == 1
    assert "X.plc:1:1: error: X.plc is not a text file" in out
    assert "Traceback" not in out + err


def test_folder_and_latin1_files(work, capsys):
    (work / "dir.plc").mkdir()
    write(work, "L.plc", "// caf\xe9\nmain() { exit(99); }\n".encode("latin-1"))
    rc, out, _err = check(capsys, "dir.plc", "L.plc")
    assert rc == 1
    assert "dir.plc:1:1: error: dir.plc is a folder, not a source file" in out
    assert "L.plc:1:1: warning: L.plc is not valid UTF-8" in out
    assert "L.plc: ok: 0 errors, 1 warning" in out


@pytest.mark.parametrize("argv", [[], ["--color=sometimes", "A.plc"], ["--bogus", "A.plc"]])
def test_usage_errors_exit_2(work, capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main(["check", *argv])
    assert exc.value.code == 2
    assert "usage: plcbuilder" in capsys.readouterr().err


# ------------------------------------------------------------ options

def test_software_option_and_software_folder(work, capsys):
    write(work, "loop.plc", GOOD)
    write(work, "software/pump.plc", GOOD)
    write(work, "other/M03.plc", GOOD)
    _rc, out, _err = check(capsys, "--software", "loop.plc")
    assert re.search(r"software procedure loop, \d+/16384 bytes", out)
    _rc, out, _err = check(capsys, "software/pump.plc", "other/M03.plc")
    assert re.search(r"software procedure pump, \d+/16384 bytes", out)
    assert re.search(r"hardware procedure M03, \d+/512 bytes", out)


def test_param_is_predefined_only_in_software_procedures(work, capsys):
    src = "main() { gvarset(100041, Param); exit(99); }\n"
    write(work, "hw.plc", src)
    write(work, "sw.plc", src)
    _rc, out, _err = check(capsys, "hw.plc")
    assert "'Param' is read but never assigned" in out
    _rc, out, _err = check(capsys, "--software", "sw.plc")
    assert "Param" not in out.replace("procedure sw", "")


def test_strict(work, capsys):
    write(work, "S.plc", "main() { if (eparam) x=1; else x=-2; exit(x); }\n")
    rc, out, _err = check(capsys, "S.plc")
    assert rc == 0
    rc, out, _err = check(capsys, "--strict", "S.plc")
    assert rc == 1
    assert "error: 'else' is not accepted by the controller's compiler (--strict)" in out
    assert "unary '-'" in out


def test_include_option_and_search_order(work, capsys):
    write(work, "hdr/mine.h", "#define MY_PIN 7\n")
    write(work, "P.plc", "#include mine.h\nmain() { portset(MY_PIN); exit(99); }\n")
    rc, out, _err = check(capsys, "P.plc")
    assert rc == 1 and "cannot find header 'mine.h'" in out
    rc, out, _err = check(capsys, "--include", "hdr", "P.plc")
    assert rc == 0, out
    rc, out, _err = check(capsys, "-I", "nowhere", "-I", "hdr", "P.plc")
    assert rc == 0, out
    # the procedure's own folder comes first
    write(work, "mine.h", "#define MY_PIN 8\n")
    write(work, "hdr/mine.h", "#define MY_PIN @\n")
    rc, out, _err = check(capsys, "--include", "hdr", "P.plc")
    assert rc == 0, out


def test_project_include_folder_and_limits(work, capsys):
    write(work, "proj/plcbuilder.toml", "[limits]\nhw_proc = 100\n")
    write(work, "proj/include/board.h", "#define PUMP 3\n")
    write(work, "proj/hardware/M10.plc", "#include board.h\nmain() { portset(PUMP); exit(99); }\n")
    rc, out, _err = check(capsys, "proj/hardware/M10.plc")
    assert rc == 0, out
    assert re.search(r"hardware procedure M10, \d+/100 bytes", out)


def test_broken_project_settings_are_reported_not_fatal(work, capsys):
    write(work, "proj/plcbuilder.toml", "[limits\nhw_proc = \n")
    write(work, "proj/hardware/M10.plc", GOOD)
    rc, out, err = check(capsys, "proj/hardware/M10.plc")
    assert rc == 0
    assert "ignoring the project's settings" in err
    assert "/512 bytes" in out


def test_defines_and_headers_point_into_the_header(work, capsys):
    write(work, "h.h", "helper() { x = y; }\n")
    write(work, "M.plc", "#include h.h\nmain() { helper(); exit(99); }\n")
    _rc, out, _err = check(capsys, "M.plc")
    assert "h.h:1:16: warning: 'y' is read but never assigned" in out
    assert "    helper() { x = y; }" in out


def test_internal_error_is_one_line_not_a_traceback(work, capsys, monkeypatch):
    import plcbuilder.api as api

    def boom(*_a, **_k):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(api, "compile_file", boom)
    monkeypatch.delenv("PLCBUILDER_DEBUG", raising=False)
    write(work, "A.plc", GOOD)
    rc, out, err = check(capsys, "A.plc")
    assert rc == 1
    assert "internal error: RuntimeError: kaboom" in err and "Traceback" not in err


# ------------------------------------------------------------ colour

class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_want_color_rules():
    tty, pipe = _Tty(), io.StringIO()
    assert term.want_color("always", pipe, {}) is True
    assert term.want_color("never", tty, {}) is False
    assert term.want_color("auto", tty, {}) is True
    assert term.want_color("auto", pipe, {}) is False
    assert term.want_color("auto", tty, {"NO_COLOR": "1"}) is False
    assert term.want_color("auto", tty, {"NO_COLOR": ""}) is True, "NO_COLOR counts when not empty"
    assert term.want_color("always", tty, {"NO_COLOR": "1"}) is True, "the flag wins over NO_COLOR"
    assert term.want_color("auto", tty, {"TERM": "dumb"}) is False


def test_colorize_kinds():
    assert term.colorize("error", "error:") == "\x1b[1;31merror:\x1b[0m"
    assert term.colorize("location", "a:1:2:").startswith("\x1b[1m")
    assert term.colorize("caret", "^~").startswith("\x1b[1;32m")
    assert term.colorize("hint", "hint:").startswith("\x1b[36m")
    assert term.colorize("warning", "warning:").startswith("\x1b[1;35m")
    assert term.colorize("unknown-kind", "x") == "x"
    line = "  portset(OUTPUT_SPINDLE); // on"
    lit = term.colorize("source", line)
    assert lit != line and ANSI.sub("", lit) == line
    assert term.colorizer(False) is None and term.colorizer(True) is term.colorize


def test_color_always_and_no_color(work, capsys, monkeypatch):
    write(work, "M05.plc", BAD)
    _rc, out, _err = check(capsys, "--color=always", "M05.plc")
    assert "\x1b[1;31merror:\x1b[0m" in out
    assert "\x1b[1mM05.plc:3:8:\x1b[0m" in out
    assert "\x1b[36mgvarset" in out, "the source line is highlighted"
    # stripped of colour it is the plain output
    _rc, plain, _err = check(capsys, "--color=never", "M05.plc")
    assert ANSI.sub("", out) == plain
    monkeypatch.setenv("NO_COLOR", "1")
    _rc, out, _err = check(capsys, "M05.plc")
    assert "\x1b[" not in out


# ------------------------------------------------------------ as a program

def test_python_m_plcbuilder_check(work):
    write(work, "A.plc", GOOD)
    write(work, "B.plc", BAD)
    run = lambda *a: subprocess.run([sys.executable, "-m", "plcbuilder", "check", *a],  # noqa: E731
                                    capture_output=True, text=True, timeout=120, cwd=work)
    ok = run("A.plc")
    assert ok.returncode == 0 and "A.plc: ok" in ok.stdout
    bad = run("A.plc", "B.plc", "missing.plc")
    assert bad.returncode == 1
    assert "B.plc:3:8: error:" in bad.stdout and "missing.plc:1:1: error:" in bad.stdout
    usage = run()
    assert usage.returncode == 2 and "Traceback" not in usage.stderr


# ------------------------------------------------------------ the manual

def test_manual_documents_every_diagnostic_code():
    manual = (ROOT / "docs" / "language.md").read_text(encoding="utf-8")
    codes = set()
    for f in glob.glob(str(ROOT / "plcbuilder" / "lang" / "*.py")):
        codes |= set(re.findall(r"\b(?:error|warning)\(\s*\"([a-z0-9-]+)\"", Path(f).read_text()))
    assert codes, "no diagnostic codes found"
    missing = sorted(c for c in codes if f"`{c}`" not in manual)
    assert missing == [], f"docs/language.md does not list: {missing}"
