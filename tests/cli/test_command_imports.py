"""Issue 26.1: a command loads only what it uses. Every command paid ~0.4 s
before it started (lark building its LALR tables, the stages of every other
command, modules no command needs to start); the ratio to a bare Python start
is measured by ``scripts/bench.py startup``: here, what each command loads."""

import subprocess
import sys

#: loaded by no command below: the parser generator, standard modules that
#: cost a start more than their use is worth there, the other commands' stages
NEVER = ("lark", "dataclasses", "inspect", "typing", "shutil", "importlib.resources",
         "zipfile", "json", "difflib", "logging", "plcbuilder.testing", "plcbuilder.trace",
         "plcbuilder.link", "plcbuilder.project.build", "plcbuilder.lang.syntax_errors",
         "plcbuilder.controller.history", "plcbuilder.controller.trigger", "PySide6", "numpy",
         "plcbuilder.lang.incremental")
#: what only ``run`` needs
RUN_ONLY = ("plcbuilder.controller", "tomllib", "random")


def loaded(tmp_path, *argv: str) -> set[str]:
    src = tmp_path / "M90.plc"
    src.write_text("main()\n{\n  exit(99);\n};\n")
    args = [a.replace("SRC", str(src)).replace("OUT", str(tmp_path / "M90.bin")) for a in argv]
    code = ("import sys, io, contextlib\n"
            "from plcbuilder.cli.main import main\n"
            "try:\n"
            "    with contextlib.redirect_stdout(io.StringIO()):\n"
            f"        rc = main({args!r})\n"
            "except SystemExit as e:\n"
            "    rc = e.code\n"
            "print(rc)\n"
            "print(' '.join(sorted(sys.modules)))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rc, mods = r.stdout.strip().splitlines()[-2:]
    assert rc == "0", r.stdout + r.stderr
    return set(mods.split())


def heavy(mods: set[str], names) -> list[str]:
    return sorted(m for m in mods if any(m == n or m.startswith(n + ".") for n in names))


def test_version_loads_no_command(tmp_path):
    mods = loaded(tmp_path, "--version")
    assert heavy(mods, NEVER + RUN_ONLY + ("plcbuilder.lang", "plcbuilder.api",
                                            "plcbuilder.cli.cmd_check")) == []


def test_check_and_compile_load_the_compiler_only(tmp_path):
    for argv in (("check", "SRC"), ("compile", "SRC", "-o", "OUT")):
        mods = loaded(tmp_path, *argv)
        assert "plcbuilder.lang.pipeline" in mods
        assert heavy(mods, NEVER + RUN_ONLY) == [], argv
        assert [m for m in mods if m.startswith("plcbuilder.cli.cmd_")] == [f"plcbuilder.cli.cmd_{argv[0]}"]


def test_run_of_one_procedure_loads_the_controller_only(tmp_path):
    mods = loaded(tmp_path, "run", "SRC")
    assert "plcbuilder.controller.session" in mods
    # (random: only for a machine whose ADC channels have noise; the default has none)
    assert heavy(mods, NEVER + ("tomllib", "random", "plcbuilder.controller.halted_state")) == []


def test_the_program_freezes_what_starting_made_and_collects_as_usual_after(tmp_path):
    """Run as the program, the command line pauses the collector while it
    starts and freezes what starting made; called with arguments (as the
    tests and other code call it) it leaves the collector alone."""
    src = tmp_path / "M90.plc"
    src.write_text("main()\n{\n  exit(99);\n};\n")
    code = ("import gc, io, sys, contextlib\n"
            "from plcbuilder.cli.main import main\n"
            "gc.collect()\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    rc = main(['check', {str(src)!r}])\n"
            "called = (rc, gc.get_freeze_count(), gc.isenabled())\n"
            f"sys.argv = ['plcbuilder', 'check', {str(src)!r}]\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    rc = main()\n"
            "print(called, (rc, gc.get_freeze_count() > 1000, gc.isenabled()))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.split("\n")[0] == "(0, 0, True) (0, True, True)", r.stdout + r.stderr
