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
