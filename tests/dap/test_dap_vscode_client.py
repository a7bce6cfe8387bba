"""Microsoft's own DAP test client, ``@vscode/debugadapter-testsupport``
(npm), runs a session against ``plcbuilder dap``: its ``hitBreakpoint``
(initialize, launch, the initialized event, setBreakpoints, configurationDone,
and the stop asserted at the breakpoint's file and line), then its
``assertStoppedLocation`` after each step over, into, out and back, an
evaluate, and the end of the procedure. Installed with npm into a folder of
the test run; skipped where node or npm is missing or the package cannot be
installed."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.dap._dap import make_project

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "@vscode/debugadapter-testsupport@1.68.0"

SCRIPT = r"""
const assert = require('assert');
const { DebugClient } = require('@vscode/debugadapter-testsupport');
const [runtime, project] = process.argv.slice(2);
const m03 = project + '/hardware/M03.plc';

(async () => {
  const dc = new DebugClient(runtime, 'dap', 'plcbuilder', { cwd: project }, true);
  dc.defaultTimeout = 60000;
  await dc.start();
  try {
    await dc.hitBreakpoint({ project, program: m03, eparam: 7 }, { path: m03, line: 5 });
    const threads = (await dc.threadsRequest()).body.threads;
    assert.deepStrictEqual(threads.map(t => t.name), ['M03']);
    const threadId = threads[0].id;
    let frame = (await dc.stackTraceRequest({ threadId })).body.stackFrames[0];
    const value = (await dc.evaluateRequest({ expression: 'count * 10 + eparam',
                                              frameId: frame.id, context: 'watch' })).body.result;
    assert.strictEqual(value, '7');
    await dc.setBreakpointsRequest({ source: { path: m03 }, breakpoints: [] });
    const steps = [['nextRequest', 6], ['stepInRequest', 13], ['stepOutRequest', 7],
                   ['stepBackRequest', 14]];          // back into helper, at its end
    for (const [request, line] of steps) {
      await Promise.all([dc[request]({ threadId }),
                         dc.assertStoppedLocation('step', { path: m03, line })]);
    }
    const scopes = (await dc.scopesRequest({ frameId: (await dc.stackTraceRequest({ threadId }))
                                                       .body.stackFrames[0].id })).body.scopes;
    const vars = (await dc.variablesRequest({ variablesReference: scopes[0].variablesReference }))
                 .body.variables;
    assert.ok(vars.some(v => v.name === 'count' && v.evaluateName === 'count'));
    const [, exited] = await Promise.all([dc.continueRequest({ threadId }),
                                          dc.waitForEvent('exited'),
                                          dc.waitForEvent('terminated')]);
    assert.strictEqual(exited.body.exitCode, 99);
    console.log('session ok');
  } finally {
    await dc.stop();
  }
})().catch(err => { console.error(err && err.stack || err); process.exit(1); });
"""


@pytest.fixture(scope="module")
def testsupport(tmp_path_factory) -> Path:
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        pytest.skip("node and npm are needed for @vscode/debugadapter-testsupport")
    where = tmp_path_factory.mktemp("npm")
    try:
        r = subprocess.run([npm, "install", "--no-audit", "--no-fund", "--silent", "--prefix",
                            str(where), PACKAGE], capture_output=True, text=True, timeout=300)
    except subprocess.TimeoutExpired:
        pytest.skip(f"npm install {PACKAGE} did not finish in 300 s")
    if r.returncode != 0:
        pytest.skip(f"npm install {PACKAGE} failed: {(r.stderr or r.stdout).strip()[-300:]}")
    return where


def test_microsofts_test_client_runs_a_session(tmp_path, testsupport):
    project = make_project(tmp_path / "proj")
    bin_dir = tmp_path / "bin"                     # 'plcbuilder' as installed
    bin_dir.mkdir()
    shim = bin_dir / "plcbuilder"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m plcbuilder "$@"\n')
    shim.chmod(0o755)
    script = tmp_path / "session.js"
    script.write_text(SCRIPT)
    env = dict(os.environ, NODE_PATH=str(testsupport / "node_modules"), PYTHONPATH=str(ROOT))
    r = subprocess.run([shutil.which("node"), str(script), str(shim), str(project)], env=env,
                       capture_output=True, text=True, timeout=240)
    assert r.returncode == 0 and "session ok" in r.stdout, (r.stdout[-2000:], r.stderr[-2000:])
