"""``plcbuilder lsp`` in a real editor: Neovim, headless, configured with the
manual's snippet for Neovim 0.7-0.10 (docs/editors.md), opens a procedure with
a mistake and asks for hover, go to definition, completion (read by Neovim's
own snippet parser) and a rename it must refuse. Skipped where Neovim is not
installed (``apt-get install neovim``)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NVIM = shutil.which("nvim")
pytestmark = pytest.mark.skipif(NVIM is None, reason="Neovim is not installed")

PROBE = r'''
local out = {}
local ok = vim.wait(30000, function() return #vim.diagnostic.get(0) > 0 end, 50)
for _, d in ipairs(vim.diagnostic.get(0)) do
  table.insert(out, string.format("diag %d:%d %s", d.lnum + 1, d.col + 1, d.message))
end
local params = { textDocument = { uri = vim.uri_from_bufnr(0) },
                 position = { line = 11, character = 3 } }
for _, r in pairs(vim.lsp.buf_request_sync(0, "textDocument/hover", params, 10000) or {}) do
  if r.result then table.insert(out, "hover " .. r.result.contents.value) end
end
params.position = { line = 12, character = 12 }
for _, r in pairs(vim.lsp.buf_request_sync(0, "textDocument/definition", params, 10000) or {}) do
  local loc = r.result[1] or r.result
  table.insert(out, string.format("definition %s:%d", loc.uri, loc.range.start.line + 1))
end
params.position = { line = 6, character = 2 }
local got = vim.lsp.buf_request_sync(0, "textDocument/completion", params, 10000) or {}
for _, r in pairs(got) do
  -- Neovim's own reading of the items: a snippet becomes the text it inserts
  for _, item in ipairs(vim.lsp.util.text_document_completion_list_to_complete_items(r.result, "")) do
    if item.abbr == "gvarset" or item.abbr == "gvarget" then
      table.insert(out, "complete " .. item.abbr .. " -> " .. item.word)
    end
  end
end
params.position = { line = 12, character = 4 }
params.newName = "x"
for _, r in pairs(vim.lsp.buf_request_sync(0, "textDocument/rename", params, 10000) or {}) do
  local err = r.err or r.error                -- (0.7 calls it error, later versions err)
  if err then
    table.insert(out, string.format("rename error %d %s data=%s", err.code, err.message,
                                    tostring(err.data)))
  end
end
local f = io.open(vim.env.PROBE_OUT, "w"); f:write(table.concat(out, "\n")); f:close()
vim.cmd("qa!")
'''


def _manual_snippet() -> str:
    text = (ROOT / "docs" / "editors.md").read_text(encoding="utf-8")
    m = re.search(r"<!-- neovim-0.7 -->\s*```lua\n(.*?)```", text, re.S)
    assert m, "docs/editors.md lost its Neovim 0.7 snippet"
    return m.group(1)


def test_neovim_with_the_manuals_snippet_gets_diagnostics_hover_and_definition(tmp_path):
    from plcbuilder import api

    project = tmp_path / "proj"
    api.create_project(project)
    m03 = project / "hardware" / "M03.plc"
    src = m03.read_text()
    assert "  portset(OUTPUT_SPINDLE);\n" in src and "  pwm01=speed;\n" in src.splitlines(True)[11]
    m03.write_text(src.replace("  portset(OUTPUT_SPINDLE);", "  portset(OUTPUT_SPINDLE;"))
    (tmp_path / "init.lua").write_text(_manual_snippet())
    (tmp_path / "probe.lua").write_text(PROBE)
    bin_dir = tmp_path / "bin"                     # 'plcbuilder' on the PATH, as installed
    bin_dir.mkdir()
    shim = bin_dir / "plcbuilder"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m plcbuilder "$@"\n')
    shim.chmod(0o755)
    out = tmp_path / "out.txt"
    env = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
               PYTHONPATH=str(ROOT), PROBE_OUT=str(out), XDG_CONFIG_HOME=str(tmp_path / "c"),
               XDG_STATE_HOME=str(tmp_path / "s"), XDG_DATA_HOME=str(tmp_path / "d"))
    subprocess.run([NVIM, "--headless", "-u", str(tmp_path / "init.lua"), "-i", "NONE",
                    "hardware/M03.plc", "-c", f"luafile {tmp_path / 'probe.lua'}"],
                   cwd=project, env=env, timeout=90, capture_output=True)
    lines = out.read_text().splitlines()
    assert "diag 13:25 unexpected ';'; expected ')' or ','" in lines, lines
    assert any(x.startswith("hover pwm01: predefined variable, PWM0 (register 7278)")
               for x in lines), lines
    assert f"definition {(project / 'include' / 'pins.h').as_uri()}:28" in lines, lines
    # issue 25.13: a placeholder per argument, as Neovim's snippet parser reads it
    assert "complete gvarset -> gvarset(addr, value)" in lines, lines
    assert "complete gvarget -> gvarget(addr)" in lines, lines
    # issue 25.10: renaming a built-in is RequestFailed with the plain sentence
    assert ("rename error -32803 portset is built in (a keyword, function, predefined variable "
            "or table name) and cannot be renamed data=nil") in lines, lines
