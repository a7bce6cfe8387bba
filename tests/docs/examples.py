"""The manual's examples, found and run (as Rust's doc tests are).

An example is a fenced block of README.md or docs/*.md that is

- a ```` ```console ```` block: ``$ COMMAND`` lines (a line ending in ``\\`` goes on
  on the next), each followed by the output it prints (stdout and stderr, as a
  terminal shows them). The output is compared: a line that is only ``…`` (or
  ``...``) stands for any number of lines, and ``…`` inside a line for any text;
- or any other shell block (or ```` ```python ```` block) right after an
  ``<!-- example -->`` comment: it runs as a script (``set -e``; Python with this
  checkout's ``python``) and must succeed (its output is not shown, so it is not
  compared).

An ``<!-- example: KEY=VALUE … -->`` comment right before a block (blank lines
between allowed) sets it up; values may be quoted as in the shell:

- ``project=NAME``: the fresh ``plcbuilder new`` project (default ``myproject``);
  ``project=`` makes none;
- ``cd=DIR``: run in that folder of the example's temporary folder;
- ``before="COMMANDS"``: hidden set-up, run first (it must succeed); ``$FIXTURES``
  is tests/docs/fixtures/, for what is too long to say in the comment;
- ``file=PATH`` (on a non-shell block, e.g. ```` ```c ````): the block is not run
  but written to PATH for this page's later examples;
- ``needs=TOOL,…``: skipped (saying so) where a program it runs is not installed;
- ``skip="WHY"``: a ``console`` block that is shown but not run, and why.

Each example runs in a fresh temporary folder (``HOME`` is ``home/me`` in it, so
``/home/me/…`` paths print as shown), with this checkout's ``plcbuilder`` first on
``PATH``, and ``scripts/run`` and ``.venv/bin/plcbuilder`` standing for it, as in a
checkout (README.md).
A ``$ COMMAND &`` runs in the background: the block goes on once it has printed as
many lines as shown under it (a server saying it is ready); background jobs are
ended (SIGTERM) when the block ends.
"""

from __future__ import annotations

import atexit
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FIXTURES = Path(__file__).resolve().parent / "fixtures"

_FENCE_OPEN = re.compile(r"^([ \t]*)(```+|~~~+)\s*([\w+-]*)[^\n]*$")
_COMMENT = re.compile(r"^<!--\s*example\b:?(.*?)-->\s*$", re.S)
_SHELLS = {"console", "sh", "shell", "bash", "", "python"}
ELLIPSES = ("…", "...")
TIMEOUT_S = 60


class ExampleError(ValueError):
    """A marking the runner cannot read (names the page and line)."""


@dataclass
class Example:
    page: Path
    line: int                    # the line of the opening fence
    info: str                    # the fence's info string
    body: str
    options: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)   # PATH -> text, from earlier file= blocks

    @property
    def id(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"

    @property
    def console(self) -> bool:
        return self.info == "console"


@dataclass
class Step:
    command: str
    expected: list[str]


def _options(text: str, where: str) -> dict:
    opts = {}
    try:
        words = shlex.split(text)
    except ValueError as exc:
        raise ExampleError(f"{where}: cannot read the example comment: {exc}") from None
    for w in words:
        key, eq, value = w.partition("=")
        if key not in ("project", "cd", "before", "file", "needs", "skip") or (not eq and key != "skip"):
            raise ExampleError(f"{where}: unknown example option {w!r} "
                               f"(project=, cd=, before=, file=, needs=, skip=)")
        opts[key] = value
    return opts


def examples(page: Path, text: Optional[str] = None) -> list[Example]:
    """The marked examples of one page, in order (``text`` stands for its content)."""
    lines = (page.read_text(encoding="utf-8") if text is None else text).splitlines()
    out: list[Example] = []
    files: dict[str, str] = {}
    pending: Optional[dict] = None       # the options of a comment just seen
    pending_line = 0
    i = 0
    while i < len(lines):
        line = lines[i]
        m = _FENCE_OPEN.match(line)
        if m:               # (a block in a list item is indented: its lines lose that)
            indent, fence, info = len(m.group(1)), m.group(2), m.group(3).lower()
            j = i + 1
            while j < len(lines) and not lines[j].lstrip().startswith(fence[:3]):
                j += 1
            body = "\n".join(l[indent:] if not l[:indent].strip() else l.lstrip()
                             for l in lines[i + 1:j])
            opts = pending
            where = f"{page.name}:{i + 1}"
            if opts is not None and "file" in opts:
                files[opts["file"]] = body + "\n"
            elif info == "console" or opts is not None:
                if info not in _SHELLS:
                    raise ExampleError(f"{where}: an example comment before a ```{info} block "
                                       f"(only shell blocks run; file=PATH writes others)")
                out.append(Example(page, i + 1, info, body, dict(opts or {}), dict(files)))
            pending = None
            i = j + 1
            continue
        if re.match(r"\s*<!--\s*example\b", line):
            k = i
            while "-->" not in lines[k] and k + 1 < len(lines):
                k += 1
            c = _COMMENT.match("\n".join(lines[i:k + 1]).strip())
            if c is None:
                raise ExampleError(f"{page.name}:{i + 1}: cannot read the example comment")
            pending, pending_line = _options(c.group(1).strip(), f"{page.name}:{i + 1}"), i + 1
            i = k + 1
            continue
        if line.strip() and pending is not None:
            raise ExampleError(f"{page.name}:{pending_line}: an example comment that no "
                               f"code block follows")
        i += 1
    return out


def steps(body: str) -> list[Step]:
    """A console block's commands, each with the output shown after it."""
    out: list[Step] = []
    lines = body.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if not line.startswith("$ "):
            if out:
                out[-1].expected.append(line)
            elif line.strip():
                raise ExampleError(f"output before the first '$ ' command: {line!r}")
            i += 1
            continue
        cmd = [line[2:]]
        while cmd[-1].endswith("\\") and i + 1 < len(lines):
            i += 1
            cmd.append(lines[i])
        out.append(Step("\n".join(cmd), []))
        i += 1
    return out


def pattern(expected: list[str]) -> re.Pattern:
    """The regular expression the shown output stands for (elisions as above)."""
    parts = []
    lines = list(expected)
    while lines and not lines[-1].strip():
        lines.pop()
    for line in lines:
        if line.strip() in ELLIPSES:
            parts.append(r"(?:[^\n]*\n)*?")
        else:
            body = ".*?".join(re.escape(p) for p in line.rstrip().split("…"))
            parts.append(body + r"[ \t]*\n")
    return re.compile("".join(parts))


def matches(expected: list[str], actual: str) -> bool:
    text = "\n".join(l.rstrip() for l in actual.rstrip("\n").splitlines())
    text = text + "\n" if text else ""
    return pattern(expected).fullmatch(text) is not None


_MARK = "@@plcb-doctest-{}@@"


def _env(tmp: Path) -> dict:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("XDG_", "PLCBUILDER_", "PLCB_"))}
    home = tmp / "home" / "me"
    home.mkdir(parents=True, exist_ok=True)
    env.update(HOME=str(home), PATH=f"{Path(sys.executable).parent}"
               f"{os.pathsep}{env.get('PATH', '')}", COLUMNS="100", NO_COLOR="1",
               PYTHONUNBUFFERED="1", LC_ALL="C.UTF-8", FIXTURES=str(FIXTURES))
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    return env


def prepare(ex: Example, tmp: Path) -> Path:
    """The example's folder: its project, files and the ``scripts/run`` stand-in."""
    tmp.mkdir(parents=True, exist_ok=True)
    plcb = Path(sys.executable).parent / "plcbuilder"
    scripts = tmp / "scripts"
    scripts.mkdir()
    (scripts / "run").write_text(f'#!/bin/sh\nexec "{plcb}" "$@"\n')
    (scripts / "run").chmod(0o755)
    (tmp / ".venv" / "bin").mkdir(parents=True)
    (tmp / ".venv" / "bin" / "plcbuilder").symlink_to(plcb)
    env = _env(tmp)
    project = ex.options.get("project", "myproject")
    if project:
        shutil.copytree(_new_project(), tmp / project, symlinks=True)
        toml = tmp / project / "plcbuilder.toml"          # its name is the folder's
        toml.write_text(toml.read_text(encoding="utf-8").replace(
            'name = "plcb_template"', f'name = "{project}"', 1), encoding="utf-8")
    for name, text in ex.files.items():
        p = tmp / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text, encoding="utf-8")
    cwd = tmp / ex.options.get("cd", "")
    cwd.mkdir(parents=True, exist_ok=True)
    return cwd


_TEMPLATE: list[Path] = []


def _new_project() -> Path:
    """A ``plcbuilder new`` project, made once per process (each example gets a copy:
    the command's output names the folder, its files do not)."""
    if not _TEMPLATE:
        base = Path(tempfile.mkdtemp(prefix="plcb-doc-template-"))
        atexit.register(shutil.rmtree, base, True)
        plcb = Path(sys.executable).parent / "plcbuilder"
        subprocess.run([str(plcb), "new", "plcb_template"], cwd=base, env=_env(base),
                       check=True, stdout=subprocess.DEVNULL, timeout=TIMEOUT_S)
        _TEMPLATE.append(base / "plcb_template")
    return _TEMPLATE[0]


def run(ex: Example, tmp: Optional[Path] = None) -> list[str]:
    """Run one example; the list of what does not hold (empty: it is true)."""
    if tmp is None:
        with tempfile.TemporaryDirectory(prefix="plcb-doc-") as d:
            return run(ex, Path(d))
    tmp = Path(tmp).resolve()
    cwd = prepare(ex, tmp)
    env = _env(tmp)
    script = "trap 'j=$(jobs -p); [ -n \"$j\" ] && kill $j 2>/dev/null; wait' EXIT\n"
    if ex.options.get("before"):
        script += (f"{{\n{ex.options['before']}\n}} >'{tmp}/.before.log' 2>&1 || "
                   f"{{ echo 'the set-up before= failed:'; cat '{tmp}/.before.log'; exit 97; }}\n")
    if not ex.console:
        body = ex.body if ex.info != "python" else f"python - <<'PLCB_EOF'\n{ex.body}\nPLCB_EOF"
        r = _bash(script + "set -e\n" + body + "\n", cwd, env)
        if r.returncode:
            return [f"{ex.id}: the commands failed (exit {r.returncode}):\n{r.stdout}"]
        return []
    todo = steps(ex.body)
    for n, st in enumerate(todo):
        # the marker between two commands keeps $? (for an `echo $?`)
        script += f"_r=$?; printf '%s\\n' '{_MARK.format(n)}'; (exit $_r)\n"
        if st.command.rstrip().endswith("&") and not st.command.rstrip().endswith("&&"):
            # in the background: what it prints by the time it has printed the lines
            # shown (a server saying it is ready), then the block goes on
            log, want = f"'{tmp}/.bg-{n}.log'", len([l for l in st.expected if l.strip()])
            script += (f": >{log}; {st.command.rstrip()[:-1]} >{log} 2>&1 &\n"
                       f"for _ in $(seq 300); do [ $(wc -l <{log}) -ge {want} ] && break; "
                       f"sleep 0.1; done; cat {log}\n")
        else:
            script += st.command + "\n"
    r = _bash(script, cwd, env)
    out = r.stdout.replace(str(tmp / "home" / "me"), "/home/me")
    if r.returncode == 97 and _MARK.format(0) not in out:
        return [f"{ex.id}: {out}"]
    chunks = re.split(r"^@@plcb-doctest-\d+@@\n", out, flags=re.M)[1:]
    chunks += [""] * (len(todo) - len(chunks))
    problems = []
    for st, actual in zip(todo, chunks):
        if not matches(st.expected, actual):
            shown = "\n".join(st.expected).rstrip("\n")
            problems.append(f"{ex.id}: $ {st.command}\n--- the manual shows:\n{shown}\n"
                            f"--- it prints:\n{actual.rstrip()}")
    return problems


def _bash(script: str, cwd: Path, env: dict) -> subprocess.CompletedProcess:
    """Run the script in its own process group; one that outlives TIMEOUT_S is ended
    whole (a server it started too) and reported with what it printed."""
    proc = subprocess.Popen(["bash", "-c", script], cwd=cwd, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True)
    try:
        out, _ = proc.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, _ = proc.communicate()
        out += f"\n(still running after {TIMEOUT_S} s: ended)\n"
    return subprocess.CompletedProcess(proc.args, proc.returncode, out)


def missing(ex: Example) -> list[str]:
    """The programs the example ``needs`` that are not installed here."""
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"
    return [t for t in ex.options.get("needs", "").split(",")
            if t and not shutil.which(t, path=path)]


def all_examples() -> list[Example]:
    return [ex for page in PAGES for ex in examples(page)]
