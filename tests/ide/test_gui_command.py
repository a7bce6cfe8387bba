"""``plcbuilder gui``: the command line, and screenshot mode (in-process
without a controller; once in a child process with the real embedded
controller running a procedure)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest
from PySide6.QtGui import QImage

from plcbuilder.cli import cmd_gui
from plcbuilder.cli.main import build_parser
from plcbuilder.ide.screenshot import parse_run

ROOT = Path(__file__).resolve().parents[2]


def make_project(root: Path) -> Path:
    (root / "hardware").mkdir(parents=True)
    (root / "hardware" / "M03.plc").write_text(
        "// M03: spindle on\n#include pins.h\nmain()\n{\n  pwm01 = eparam;\n"
        "  portset(OUTPUT_SPINDLE);\n  exit(99);\n};\n")
    (root / "hardware" / "M05.plc").write_text(
        "#include pins.h\nmain() { portclear(OUTPUT_SPINDLE); exit(99); };\n")
    return root


def gui(*args) -> subprocess.CompletedProcess:
    """``plcbuilder gui ARGS`` in a child process, offscreen, its output captured."""
    return subprocess.run([sys.executable, "-m", "plcbuilder", "gui", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT,
                          env=dict(os.environ, QT_QPA_PLATFORM="offscreen"), timeout=120)


def test_parser_and_bad_usage(tmp_path, capsys):
    args = build_parser().parse_args(["gui", str(tmp_path), "--screenshot", "x.png", "--run",
                                      "M03:5", "--after", "250"])
    assert args.project == tmp_path and args.run == "M03:5" and args.after == 250
    assert cmd_gui.run(build_parser().parse_args(["gui", "--run", "M03"])) == 2
    assert cmd_gui.run(build_parser().parse_args(["gui", str(tmp_path / "nope")])) == 2
    assert "no such project" in capsys.readouterr().err


def test_parse_run():
    assert parse_run("M03") == ("M03", 0)
    assert parse_run("M03:0x10") == ("M03", 16)
    assert parse_run(None) is None
    with pytest.raises(ValueError):
        parse_run(":5")
    with pytest.raises(ValueError):
        parse_run("M03:x")


def test_importing_the_cli_does_not_load_qt():
    code = ("import sys, plcbuilder.cli.main as m; m.build_parser(); "
            "print('PySide6' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "False", out.stderr


def test_screenshot_without_a_controller(qtbot, tmp_path):
    from plcbuilder.ide.app import main
    project = make_project(tmp_path / "proj")
    out = tmp_path / "shot.png"
    rc = main(str(project), screenshot=str(out), after_ms=50, start_controller=False,
              settings_path=str(tmp_path / "s.ini"))
    assert rc == 0
    img = QImage(str(out))
    assert img.width() >= 1000 and img.height() >= 600
    assert (project / "build" / "eeprom.rom").is_file()


def test_screenshot_running_a_procedure_on_the_embedded_controller(tmp_path):
    project = make_project(tmp_path / "proj")
    out = tmp_path / "run.png"
    proc = gui(project, "--screenshot", out, "--run", "M03:1000", "--after", "300",
               "--settings", tmp_path / "s.ini")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "wrote" in proc.stdout
    assert QImage(str(out)).width() >= 1000


def test_run_without_a_project_says_so(tmp_path):
    """``--run`` with no project: it says a project is needed (it said "the
    controller did not start": the controller starts with a project)."""
    proc = gui("--screenshot", tmp_path / "x.png", "--run", "M03", "--after", "100",
               "--settings", tmp_path / "s.ini")
    assert proc.returncode == 1
    assert "--run needs a project" in proc.stderr and "did not start" not in proc.stderr


def test_run_that_halts_at_a_breakpoint_says_where(tmp_path):
    """A saved breakpoint halts the procedure ``--run`` starts: the message says
    where it halted (it said "the simulation did not reach t = ..."), and the
    picture is written."""
    from plcbuilder.ide.settings import Settings
    from plcbuilder.project.new import create_project
    project = create_project(tmp_path / "ex").root
    st = Settings(str(tmp_path / "s.ini"))
    st.save_breakpoints(project, [{"path": "hardware/M80.plc", "line": 31, "enabled": True,
                                   "condition": "", "hit": None, "log": ""}])
    st.sync()
    out = tmp_path / "halt.png"
    proc = gui(project, "--screenshot", out, "--run", "M80", "--after", "3000",
               "--settings", tmp_path / "s.ini")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "halted before t = " in proc.stderr and "M80.plc:31" in proc.stderr, proc.stderr
    assert "did not reach" not in proc.stderr
    assert QImage(str(out)).width() >= 1000


def test_trace_needs_the_screenshot_and_at_most_two(tmp_path, capsys):
    parse = build_parser().parse_args
    assert cmd_gui.run(parse(["gui", str(tmp_path), "--trace", "a.plctrace"])) == 2
    assert "--trace needs --screenshot" in capsys.readouterr().err
    assert cmd_gui.run(parse(["gui", str(tmp_path), "--screenshot", "x.png", "--trace", "a",
                              "--trace", "b", "--trace", "c"])) == 2
    assert "at most twice" in capsys.readouterr().err


def test_screenshot_of_two_traces_compared(tmp_path):
    """Issue 11: the overlay of a comparison, as a picture (docs/images/trace-compare.png)."""
    from plcbuilder import api
    project = make_project(tmp_path / "proj")
    for name, on in (("a", 1), ("b", 0)):
        api.save_trace(api.Trace(0, 99, {"out 3": ("bit", [(0, 0), (40, on)])}),
                       tmp_path / f"{name}.plctrace")
    (tmp_path / "bad.plctrace").write_text("no trace")

    def shot(*traces):
        out = tmp_path / "cmp.png"
        args = [project, "--screenshot", out, "--after", "50", "--settings", tmp_path / "s.ini"]
        for t in traces:
            args += ["--trace", tmp_path / t]
        return gui(*args), out
    proc, out = shot("a.plctrace", "b.plctrace")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert QImage(str(out)).width() >= 1000
    proc, _out = shot("a.plctrace", "bad.plctrace")
    assert proc.returncode == 1 and "not a trace file" in proc.stderr


def test_screenshot_of_a_trace_with_a_watched_variable(tmp_path):
    """docs/images/watched-variables.png: a trace whose M80.sens rises at its
    trigger is pictured with the variable's lane, in the variables' colour."""
    from plcbuilder import api
    from plcbuilder.ide.panels.style import LIGHT_PLOTS
    project = make_project(tmp_path / "proj")
    trace = api.Trace(0, 99, {"in 2": ("bit", [(0, 0), (40, 1)]),
                              "M80.sens": ("int", [(0, 0), (40, 1)]),
                              "M80.statez": ("int", [(0, 0), (40, 1), (70, 2)])},
                      meta={"trigger": {"spec": "M80.sens bit 0 rise", "t_ms": 40,
                                        "pre_ms": 40, "post_ms": 59, "mode": "single"}})
    api.save_trace(trace, tmp_path / "cap.plctrace")
    out = tmp_path / "watched.png"
    proc = gui(project, "--screenshot", out, "--after", "50", "--settings", tmp_path / "s.ini",
               "--trace", tmp_path / "cap.plctrace")
    assert proc.returncode == 0, proc.stderr[-2000:]
    image = QImage(str(out))
    lane = sum(image.pixelColor(x, y).name() == LIGHT_PLOTS.variable
               for y in range(0, image.height(), 1) for x in range(0, image.width(), 2))
    assert lane > 50


def test_the_launcher_opens_a_procedure_with_its_project(tmp_path):
    """The launcher runs ``gui FILE``: a .plc file opens its project and the file
    (the desktop's "Open With PLC Builder")."""
    from plcbuilder.ide.app import project_of
    from plcbuilder.project.new import create_project
    root = create_project(tmp_path / "p").root
    assert project_of(root / "hardware" / "M03.plc") == root.resolve()
    assert project_of(root / "plcbuilder.toml") == root.resolve()
    loose = tmp_path / "loose"
    (loose / "hardware").mkdir(parents=True)
    (loose / "hardware" / "X.plc").write_text("main(){}")
    assert project_of(loose / "hardware" / "X.plc") == loose.resolve()
