"""A controller of one's own: ``plcbuilder controller`` as a child process.

The IDE's embedded controller, and the tests' real one::

    proc = ControllerProcess(["--image", "build/eeprom.rom"])   # starts; returns at once
    endpoint = proc.wait_endpoint(timeout=30)                    # address and token
    client = proc.connect()
    ...
    proc.stop()          # SIGTERM: __HANDLER_EXIT runs, the process exits

The child listens on a free loopback port and writes its address and token to a
runtime file in a private folder (0700), never the user's own. It ends with
this process: on Linux the kernel sends it SIGTERM when its parent dies
(``PR_SET_PDEATHSIG``, so even ``kill -9`` of the IDE leaves no orphan);
elsewhere it watches its parent (``--parent``); and at interpreter exit every
child still running is stopped. Its standard error goes to a file in the same
folder: :meth:`ControllerProcess.why_dead` quotes its last lines.
"""

from __future__ import annotations

import atexit
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import weakref
from pathlib import Path
from typing import TYPE_CHECKING, Optional, Sequence

from plcbuilder.link import runtime

if TYPE_CHECKING:
    from plcbuilder.link.client import Client


def _link_error(text: str) -> Exception:
    """The client's LinkError (the client loads when it is needed: starting a
    child, as the IDE does before its window paints, does not wait for it)."""
    from plcbuilder.link.client import LinkError
    return LinkError(text)

__all__ = ["ControllerProcess"]


class ControllerProcess:
    """One ``plcbuilder controller`` child process and its private runtime folder."""

    def __init__(self, extra_args: Sequence[str] = (), *, python: Optional[str] = None):
        self.dir = Path(tempfile.mkdtemp(prefix="plcbuilder-controller-"))   # 0700
        self.runtime_file = self.dir / runtime.FILE_NAME
        self.log_path = self.dir / "controller.log"
        env = dict(os.environ)
        env[runtime.ENV_FILE] = str(self.runtime_file)
        env.setdefault("PYTHONUNBUFFERED", "1")
        args = ["controller", "--port", "0", "--runtime-file", str(self.runtime_file),
                "--parent", str(os.getpid()), *extra_args]
        exe = python or sys.executable
        if sys.platform.startswith("linux"):
            # end with this process even when it is killed (PR_SET_PDEATHSIG)
            code = ("import ctypes, signal, sys\n"
                    "try:\n ctypes.CDLL(None).prctl(1, signal.SIGTERM)\n"
                    "except Exception:\n pass\n"
                    "from plcbuilder.cli.main import main\n"
                    f"sys.argv[0] = 'plcbuilder'\nraise SystemExit(main({args!r}))\n")
            cmd = [exe, "-c", code]
        else:
            cmd = [exe, "-m", "plcbuilder", *args]
        self._log = open(self.log_path, "wb")       # a file, not a pipe nobody reads
        self.popen = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=self._log,
                                      stderr=self._log, env=env, close_fds=True)
        self._stopped = False
        _CHILDREN.add(self)

    @classmethod
    def start(cls, *, machine=None, variables=None, image=None, speed: str = "realtime",
              extra_args: Sequence[str] = (), python: Optional[str] = None,
              timeout: float = 30.0) -> "ControllerProcess":
        """Start one and wait until it listens; raises LinkError saying why it did not."""
        args = ["--speed", str(speed)]
        for opt, value in (("--machine", machine), ("--variables", variables), ("--image", image)):
            if value is not None:
                args += [opt, str(value)]
        from plcbuilder.link.client import LinkError
        proc = cls([*args, *extra_args], python=python)
        try:
            proc.wait_endpoint(timeout)
        except LinkError:
            proc.stop()
            raise
        return proc

    # ------------------------------------------------------------ state
    @property
    def pid(self) -> int:
        return self.popen.pid

    @property
    def running(self) -> bool:
        return self.popen.poll() is None

    def alive(self) -> bool:
        return self.running

    def endpoint(self) -> Optional[runtime.Endpoint]:
        """Its address and token once it listens, else None."""
        try:
            ep = runtime.read(self.runtime_file)
        except runtime.RuntimeFileError:
            return None
        return ep if ep.pid == self.popen.pid else None

    def wait_endpoint(self, timeout: float = 30.0,
                      cancel: Optional[threading.Event] = None) -> Optional[runtime.Endpoint]:
        """Wait until it listens. Raises LinkError when it died or did not start in
        time (a hung child is stopped); returns None when ``cancel`` was set."""
        deadline = time.monotonic() + timeout
        while True:
            ep = self.endpoint()
            if ep is not None:
                return ep
            if not self.running:
                raise _link_error(f"the controller did not start: {self.why_dead()}")
            if time.monotonic() > deadline:
                tail = self.stderr_tail()
                self.stop()                     # hung: the next try starts a fresh one
                raise _link_error(f"the controller did not start within {timeout:g} s"
                                  + (f": {tail}" if tail else ""))
            if cancel is not None:
                if cancel.wait(0.02):
                    return None
            else:
                time.sleep(0.02)

    @property
    def address(self) -> tuple[str, int]:
        ep = self.endpoint()
        if ep is None:
            raise _link_error("the controller is not listening")
        return ep.host, ep.port

    def connect(self, **kwargs) -> Client:
        from plcbuilder.link.client import Client
        ep = self.endpoint()
        if ep is None:
            raise _link_error("the controller is not listening")
        return Client.connect(ep.host, ep.port, ep.token, **kwargs)

    def why_dead(self) -> str:
        code = self.popen.poll()
        if code is None:
            return "the controller process is running"
        if code < 0:
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = f"signal {-code}"
            text = f"the controller process was killed ({name})"
        else:
            text = f"the controller process exited with status {code}"
        tail = self.stderr_tail()
        return f"{text}: {tail}" if tail else text

    def stderr_tail(self, lines: int = 3) -> str:
        try:
            with open(self.log_path, "rb") as f:        # our own log: read its end only
                f.seek(max(0, f.seek(0, os.SEEK_END) - 4000))
                data = f.read(4000).decode("utf-8", "replace")
        except OSError:
            return ""
        rows = [r for r in data.strip().splitlines() if r.strip()]
        return " | ".join(rows[-lines:])

    # ------------------------------------------------------------- stop
    def stop(self, timeout: float = 15.0) -> Optional[int]:
        """SIGTERM (the controller runs __HANDLER_EXIT), wait, kill if it will not
        end; remove the private folder. Returns the exit status."""
        p = self.popen
        if p.poll() is None:
            try:
                p.terminate()
                p.wait(timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                try:
                    p.wait(timeout)
                except subprocess.TimeoutExpired:
                    pass
            except OSError:
                pass
        if not self._stopped:
            self._stopped = True
            try:
                self._log.close()
            except OSError:
                pass
            shutil.rmtree(self.dir, ignore_errors=True)
        return p.poll()


_CHILDREN: "weakref.WeakSet[ControllerProcess]" = weakref.WeakSet()


def _reap_children() -> None:           # at interpreter exit: no orphans
    for c in list(_CHILDREN):
        try:
            c.stop(1.0)
        except Exception:  # noqa: BLE001 - exiting: nothing more can be done
            pass


atexit.register(_reap_children)
