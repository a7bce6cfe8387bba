"""The manual's VS Code ``package.json`` (docs/editors.md) starts the debug
adapter as VS Code would (issue 25.5): its ``debuggers`` entry is resolved by
VS Code's own rules (``ExecutableDebugAdapter.platformAdapterExecutable``: a
``runtime`` is run as given, looked up on the PATH, with ``runtimeArgs``, then
``program`` joined to the extension's folder, then ``args``), and the command
that gives answers ``initialize``. The manual had ``"program": "plcbuilder"``,
which VS Code looks for inside the extension folder, so the adapter never
started."""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
from pathlib import Path

from tests.dap._dap import DapClient, initialize

ROOT = Path(__file__).resolve().parents[2]


def _package_json() -> dict:
    text = (ROOT / "docs" / "editors.md").read_text(encoding="utf-8")
    blocks = [json.loads(b) for b in re.findall(r"```json\n(.*?)```", text, re.S)
              if '"debuggers"' in b]
    assert len(blocks) == 1, "docs/editors.md: one package.json with a debuggers entry"
    return blocks[0]


def _vscode_command(package: dict, extension_folder: Path) -> list[str]:
    """What VS Code runs for the debugger of type plcbuilder (Linux)."""
    dbg = next(d for d in package["contributes"]["debuggers"] if d["type"] == "plcbuilder")
    dbg = {**dbg, **dbg.get("linux", {})}
    runtime, program = dbg.get("runtime"), dbg.get("program")
    if program is not None and not os.path.isabs(program):
        program = str(extension_folder / program)
    if runtime is not None and runtime.startswith("./"):
        runtime = str(extension_folder / runtime)
    if runtime:
        return [runtime, *dbg.get("runtimeArgs", []), *([program] if program else []),
                *dbg.get("args", [])]
    assert program, "the debuggers entry names neither runtime nor program"
    return [program, *dbg.get("args", [])]


def test_the_manuals_package_json_starts_the_adapter(tmp_path):
    import subprocess

    package = _package_json()
    assert package["contributes"]["breakpoints"] == [{"language": "plc"}]
    extension = tmp_path / "extensions" / "plcbuilder"
    extension.mkdir(parents=True)
    (extension / "package.json").write_text(json.dumps(package))
    command = _vscode_command(package, extension)
    assert command == ["plcbuilder", "dap"]
    bin_dir = tmp_path / "bin"                     # 'plcbuilder' on the PATH, as installed
    bin_dir.mkdir()
    shim = bin_dir / "plcbuilder"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m plcbuilder "$@"\n')
    shim.chmod(0o755)
    path = f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"
    exe = shutil.which(command[0], path=path)
    assert exe is not None
    proc = subprocess.Popen([exe, *command[1:]], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=tmp_path,
                            env=dict(os.environ, PATH=path, PYTHONPATH=str(ROOT)))
    dap = DapClient(proc)
    try:
        caps = initialize(dap)
        assert caps["supportsConfigurationDoneRequest"] and caps["supportsStepBack"]
        dap.ok("disconnect")
        proc.wait(20)
        assert proc.returncode == 0
    finally:
        dap.close()


def test_the_old_snippet_would_not_have_started_it(tmp_path):
    """The resolution above is VS Code's: the manual's old entry pointed into
    the extension folder, where no plcbuilder is."""
    old = {"contributes": {"debuggers": [{"type": "plcbuilder", "program": "plcbuilder",
                                          "args": ["dap"]}]}}
    command = _vscode_command(old, tmp_path / "ext")
    assert command == [str(tmp_path / "ext" / "plcbuilder"), "dap"]
    assert not Path(command[0]).exists()
