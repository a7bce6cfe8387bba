"""The runtime file: private, atomic, found by clients, removed on exit."""

import json
import os
import stat
import sys

import pytest

from plcbuilder.link import runtime
from plcbuilder.link.runtime import Endpoint, RuntimeFileError

posix_only = pytest.mark.skipif(sys.platform == "win32", reason="POSIX permissions")


def test_default_path_prefers_xdg_runtime_dir(tmp_path):
    env = {"XDG_RUNTIME_DIR": str(tmp_path)}
    assert runtime.default_path(env) == tmp_path / "plcbuilder" / "controller.json"
    env = {"XDG_RUNTIME_DIR": str(tmp_path / "missing"), "XDG_CACHE_HOME": str(tmp_path / "c")}
    assert runtime.default_path(env) == tmp_path / "c" / "plcbuilder" / "run" / "controller.json"
    env = {"XDG_RUNTIME_DIR": "relative", "PLCBUILDER_CONTROLLER_FILE": str(tmp_path / "f.json")}
    assert runtime.default_path(env) == tmp_path / "f.json"
    if sys.platform != "win32":
        assert runtime.default_path({"XDG_CACHE_HOME": "rel"}).parts[-4:] == \
            (".cache", "plcbuilder", "run", "controller.json")


@posix_only
def test_written_private_and_atomically(tmp_path):
    path = tmp_path / "run" / "plcbuilder" / "controller.json"
    ep = Endpoint("127.0.0.1", 4242, runtime.new_token(), os.getpid())
    old = os.umask(0)
    try:
        assert runtime.write(ep, path) == path
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert stat.S_IMODE(path.parent.stat().st_mode) == 0o700
    assert json.loads(path.read_text()) == ep.as_dict()
    assert runtime.read(path) == ep
    assert os.listdir(path.parent) == ["controller.json"]      # no temporary left
    ep2 = Endpoint("127.0.0.1", 4243, runtime.new_token(), os.getpid())
    runtime.write(ep2, path)                                   # replaced whole
    assert runtime.read(path) == ep2
    assert not runtime.remove(ep, path)                        # not ours any more: kept
    assert path.exists()
    assert runtime.remove(ep2, path)
    assert not path.exists()
    assert not runtime.remove(ep2, path)


def test_tokens_are_fresh_and_long():
    tokens = {runtime.new_token() for _ in range(50)}
    assert len(tokens) == 50 and min(len(t) for t in tokens) >= 40


@pytest.mark.parametrize("text", ["", "{", "[]", '{"host": "h"}',
                                  '{"host": 1, "port": 2, "token": "t", "pid": 3}',
                                  '{"host": "h", "port": 0, "token": "t", "pid": 3}',
                                  '{"host": "h", "port": "80", "token": "t", "pid": 3}'])
def test_damaged_files_are_reported(tmp_path, text):
    p = tmp_path / "c.json"
    p.write_text(text)
    with pytest.raises(RuntimeFileError, match="damaged"):
        runtime.read(p)


def test_missing_file(tmp_path):
    with pytest.raises(RuntimeFileError, match="no runtime file"):
        runtime.read(tmp_path / "nope.json")


def test_pid_alive():
    assert runtime.pid_alive(os.getpid())
    assert not runtime.pid_alive(0)


# ------------------------------------------------------------------ issue 17 point 11

@posix_only
def test_a_folder_other_users_can_write_is_refused(tmp_path):
    folder = tmp_path / "shared"
    folder.mkdir()
    path = folder / "controller.json"
    ep = Endpoint("127.0.0.1", 4242, runtime.new_token(), os.getpid())
    runtime.write(ep, path)
    os.chmod(folder, 0o1777)                 # as /tmp is
    with pytest.raises(RuntimeFileError, match="other users can write"):
        runtime.read(path)
    with pytest.raises(RuntimeFileError, match="other users can write"):
        runtime.write(ep, path)
    os.chmod(folder, 0o700)
    assert runtime.read(path) == ep
    os.chmod(path, 0o622)
    with pytest.raises(RuntimeFileError, match="other users can write"):
        runtime.read(path)


@posix_only
@pytest.mark.skipif(not hasattr(os, "getuid") or os.getuid() != 0, reason="needs chown")
def test_a_file_or_folder_of_another_user_is_refused(tmp_path):
    folder = tmp_path / "theirs"
    path = folder / "controller.json"
    ep = Endpoint("127.0.0.1", 4242, runtime.new_token(), os.getpid())
    runtime.write(ep, path)
    os.chown(path, 12345, -1)
    with pytest.raises(RuntimeFileError, match="belongs to user 12345"):
        runtime.read(path)
    os.chown(path, 0, -1)
    os.chown(folder, 12345, -1)
    with pytest.raises(RuntimeFileError, match="belongs to user 12345"):
        runtime.read(path)


@posix_only
def test_a_client_refuses_a_runtime_file_in_a_shared_folder(tmp_path, monkeypatch):
    from plcbuilder.link.client import Client, NotRunningError
    folder = tmp_path / "shared"
    path = folder / "controller.json"
    runtime.write(Endpoint("127.0.0.1", 4242, "t" * 43, os.getpid()), path)
    os.chmod(folder, 0o777)
    with pytest.raises(NotRunningError, match="other users can write"):
        Client.connect(runtime_file=path, connect_timeout=1)


def _controller(path):
    import subprocess
    return subprocess.Popen([sys.executable, "-m", "plcbuilder", "controller", "--port", "0",
                             "--runtime-file", str(path)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def _wait_pid(path, pid, timeout=30):
    import time
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if runtime.read(path).pid == pid:
                return
        except RuntimeFileError:
            pass
        time.sleep(0.05)
    raise AssertionError(f"the runtime file never named process {pid}")


@posix_only
def test_stopping_the_newer_of_two_controllers_gives_the_file_back(tmp_path):
    path = tmp_path / "rt" / "controller.json"
    older = _controller(path)
    try:
        _wait_pid(path, older.pid)
        newer = _controller(path)
        try:
            _wait_pid(path, newer.pid)
        finally:
            newer.terminate()
            newer.wait(30)
        assert runtime.read(path).pid == older.pid      # the older one is found again
    finally:
        older.terminate()
        older.wait(30)
    assert not path.exists()
