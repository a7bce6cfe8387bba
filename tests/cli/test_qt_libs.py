"""Missing X11 libraries for Qt are named with the apt-get line that installs
them, by ``scripts/run`` and ``plcbuilder gui``, before Qt stops with "could not
load the Qt platform plugin xcb" (issue 13, defect 11); and ``plcbuilder
--settings F`` is the IDE's option, as ``plcbuilder gui --settings F`` is."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from plcbuilder.cli import cmd_gui, qt_libs
from plcbuilder.cli.main import main

ROOT = Path(__file__).resolve().parents[2]

LDD_MISSING = """\
\tlinux-vdso.so.1 (0x00007ffd)
\tlibQt6XcbQpa.so.6 => /venv/PySide6/Qt/lib/libQt6XcbQpa.so.6 (0x00007f)
\tlibxcb-cursor.so.0 => not found
\tlibxcb-icccm.so.4 => not found
\tlibxkbcommon-x11.so.0 => not found
\tlibxcb-cursor.so.0 => not found
\tlibc.so.6 => /lib/x86_64-linux-gnu/libc.so.6 (0x00007f)
"""


def fake_ldd(tmp_path: Path, output: str) -> str:
    script = tmp_path / "ldd"
    (tmp_path / "ldd.out").write_text(output)
    script.write_text(f"#!/bin/sh\ncat '{tmp_path / 'ldd.out'}'\n")
    script.chmod(0o755)
    return str(script)


def test_the_apt_line_names_the_packages_of_the_missing_libraries():
    libs = qt_libs.missing_in(LDD_MISSING)
    assert libs == ["libxcb-cursor.so.0", "libxcb-icccm.so.4", "libxkbcommon-x11.so.0"]
    assert qt_libs.apt_line(libs) == ("sudo apt-get install -y libxcb-cursor0 libxcb-icccm4 "
                                      "libxkbcommon-x11-0")
    assert qt_libs.packages_for(["libunheard.so.3"]) == ["libunheard.so.3"]


def test_what_this_machine_lacks_is_named_by_its_package():
    """On this machine, with the real plugin and the real ldd: every library the
    loader cannot find has its Debian package in the table (so the printed
    apt-get line installs it), and the module's exit status says whether
    anything is missing (CI machines differ: both outcomes are checked)."""
    plugin = qt_libs.xcb_plugin()
    if plugin is None or not shutil.which("ldd"):
        pytest.skip("no xcb plugin or no ldd")
    missing = qt_libs.missing_libraries(plugin)
    assert [lib for lib in missing if lib not in qt_libs.PACKAGES] == []
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("PLCBUILDER_LDD", None)
    out = subprocess.run([sys.executable, "-m", "plcbuilder.cli.qt_libs"], env=env,
                         capture_output=True, text=True, cwd=ROOT)
    if missing:
        assert out.returncode == 1 and qt_libs.apt_line(missing) in out.stderr
    else:
        assert out.returncode == 0 and out.stderr == ""


def test_the_module_prints_the_line_and_fails(tmp_path):
    env = dict(os.environ, PLCBUILDER_LDD=fake_ldd(tmp_path, LDD_MISSING),
               PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-m", "plcbuilder.cli.qt_libs"], env=env,
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 1
    assert "sudo apt-get install -y libxcb-cursor0 libxcb-icccm4 libxkbcommon-x11-0" in out.stderr


def test_scripts_run_stops_before_qt_with_the_line(tmp_path):
    """scripts/run in a checkout whose .venv is ready (a stand-in for its plcbuilder)."""
    if qt_libs.xcb_plugin() is None:
        pytest.skip("no xcb plugin")
    checkout = tmp_path / "checkout"
    (checkout / "scripts").mkdir(parents=True)
    for name in ("run", "_venv.sh"):
        shutil.copy2(ROOT / "scripts" / name, checkout / "scripts" / name)
    (checkout / "pyproject.toml").write_text("")
    venv_bin = checkout / ".venv" / "bin"
    venv_bin.mkdir(parents=True)
    (venv_bin / "python").write_text(f"#!/bin/sh\nexec '{sys.executable}' \"$@\"\n")
    (venv_bin / "python").chmod(0o755)
    (venv_bin / "plcbuilder").write_text("#!/bin/sh\necho IDE STARTED \"$@\"\n")
    (venv_bin / "plcbuilder").chmod(0o755)
    (checkout / ".venv" / ".installed").write_text("")
    env = dict(os.environ, DISPLAY=":99", PYTHONPATH=str(ROOT))
    env.pop("WAYLAND_DISPLAY", None)
    env.pop("QT_QPA_PLATFORM", None)
    env["PLCBUILDER_LDD"] = fake_ldd(tmp_path, LDD_MISSING)
    out = subprocess.run(["bash", str(checkout / "scripts" / "run"), "--settings", "x.ini"],
                         env=env, capture_output=True, text=True)
    assert out.returncode == 1 and "IDE STARTED" not in out.stdout
    assert "sudo apt-get install -y libxcb-cursor0 libxcb-icccm4 libxkbcommon-x11-0" in out.stderr
    # with the libraries there, it starts the IDE; other commands never check
    env["PLCBUILDER_LDD"] = fake_ldd(tmp_path, "\tlibc.so.6 => /lib/libc.so.6 (0x1)\n")
    out = subprocess.run(["bash", str(checkout / "scripts" / "run")], env=env,
                         capture_output=True, text=True)
    assert out.returncode == 0 and "IDE STARTED" in out.stdout
    env["PLCBUILDER_LDD"] = fake_ldd(tmp_path, LDD_MISSING)
    out = subprocess.run(["bash", str(checkout / "scripts" / "run"), "check", "x.plc"], env=env,
                         capture_output=True, text=True)
    assert "IDE STARTED check x.plc" in out.stdout


def test_plcbuilder_gui_says_it_too(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PLCBUILDER_LDD", fake_ldd(tmp_path, LDD_MISSING))
    monkeypatch.setenv("QT_QPA_PLATFORM", "xcb")
    if qt_libs.xcb_plugin() is None:
        pytest.skip("no xcb plugin")
    assert main(["gui", "--no-controller"]) == 1
    assert "apt-get install -y libxcb-cursor0" in capsys.readouterr().err


def test_settings_is_an_option_of_plcbuilder_itself(tmp_path, monkeypatch):
    seen = {}
    monkeypatch.setattr(cmd_gui, "run", lambda args: seen.update(vars(args)) or 0)
    ini = tmp_path / "ide.ini"
    assert main(["--settings", str(ini), "--no-controller"]) == 0
    assert seen["command"] == "gui" and seen["settings"] == ini and seen["no_controller"]
    assert main([f"--settings={ini}"]) == 0 and seen["settings"] == ini
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0


def test_the_check_runs_while_the_ide_loads(tmp_path):
    """Issue 26.5: ``ldd`` (a process of its own, a hundredth of a second and
    more) starts before the IDE's modules load and is asked for its answer
    after, not before them, on the way to the window."""
    if qt_libs.xcb_plugin() is None:
        pytest.skip("no xcb plugin")
    marks = tmp_path / "marks"
    ldd = tmp_path / "ldd"
    # the fake ldd answers once the IDE's modules began to load (or after 10 s,
    # when the command waited for it first): the order, not the machine's load, decides
    ldd.write_text(f"#!/bin/sh\necho ldd-started >> '{marks}'\n"
                   f"for i in $(seq 100); do grep -q ide-import '{marks}' && break; "
                   f"sleep 0.1; done\n"
                   f"echo ldd-done >> '{marks}'\ncat '{tmp_path / 'ldd.out'}'\n")
    ldd.chmod(0o755)
    (tmp_path / "ldd.out").write_text(LDD_MISSING)
    code = f"""
import sys
class Hook:
    def find_spec(self, name, path, target=None):
        if name == "plcbuilder.ide.app":
            open({str(marks)!r}, "a").write("ide-import\\n")
        return None
sys.meta_path.insert(0, Hook())
from plcbuilder.cli.main import main
raise SystemExit(main(["gui", "--no-controller"]))
"""
    env = dict(os.environ, QT_QPA_PLATFORM="xcb", DISPLAY=":99", PLCBUILDER_LDD=str(ldd),
               PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 1 and "apt-get install -y libxcb-cursor0" in out.stderr
    order = marks.read_text().split()
    assert order.index("ldd-started") < order.index("ide-import") < order.index("ldd-done"), order
