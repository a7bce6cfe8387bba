"""``plcbuilder desktop-install``: the launcher, the icon and the file types in
a temporary XDG data folder, checked with the freedesktop.org tools themselves
(desktop-file-validate from Debian's desktop-file-utils, update-mime-database
from shared-mime-info) where they are installed."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from tests.cli._run import run_cli

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="freedesktop.org desktop integration is for Linux")


@pytest.fixture
def xdg(tmp_path, monkeypatch):
    data, config = tmp_path / "data", tmp_path / "config"
    monkeypatch.setenv("XDG_DATA_HOME", str(data))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(config))
    config.mkdir()
    # the user's own defaults stay as they are
    (config / "mimeapps.list").write_text("[Default Applications]\ntext/plain=gedit.desktop;\n"
                                          "\n[Added Associations]\ntext/x-c=kate.desktop;\n")
    return data, config


def test_desktop_install_writes_a_valid_launcher_icon_and_file_types(xdg, capsys):
    data, config = xdg
    code, out, err = run_cli(capsys, "desktop-install", "--color", "never")
    assert code == 0, err
    entry = data / "applications" / "plcbuilder.desktop"
    icon = data / "icons" / "hicolor" / "scalable" / "apps" / "plcbuilder.svg"
    mime = data / "mime" / "packages" / "plcbuilder.xml"
    for path in (entry, icon, mime):
        assert path.is_file() and f"wrote {path}" in out
    text = entry.read_text()
    assert "Icon=plcbuilder\n" in text and "Categories=Development;IDE;\n" in text
    assert f"Exec={sys.executable} -m plcbuilder gui %f\n" in text
    assert "MimeType=text/x-plcbuilder-plc;application/x-plcbuilder-project;inode/directory;" \
        in text
    assert icon.read_bytes().lstrip().startswith(b"<")
    apps = (config / "mimeapps.list").read_text()
    assert "text/x-plcbuilder-plc=plcbuilder.desktop;" in apps
    assert "application/x-plcbuilder-project=plcbuilder.desktop;" in apps
    assert "text/plain=gedit.desktop;" in apps and "text/x-c=kate.desktop;" in apps
    assert "inode/directory=plcbuilder" not in apps        # offered, never the default

    validate = shutil.which("desktop-file-validate")
    if validate is None:
        pytest.skip("desktop-file-validate is not installed (Debian: desktop-file-utils)")
    r = subprocess.run([validate, str(entry)], capture_output=True, text=True)
    assert r.returncode == 0 and not r.stdout.strip(), r.stdout + r.stderr


def test_the_file_types_are_what_the_mime_database_reads(xdg, capsys):
    data, _config = xdg
    if shutil.which("update-mime-database") is None:
        pytest.skip("update-mime-database is not installed (Debian: shared-mime-info)")
    code, out, err = run_cli(capsys, "desktop-install", "--color", "never")
    assert code == 0 and "ran update-mime-database" in out, out + err
    globs = (data / "mime" / "globs2").read_text()
    assert "text/x-plcbuilder-plc:*.plc" in globs
    assert "application/x-plcbuilder-project:plcbuilder.toml" in globs


def test_remove_takes_it_all_away_and_keeps_the_users_defaults(xdg, capsys):
    data, config = xdg
    assert run_cli(capsys, "desktop-install")[0] == 0
    code, out, err = run_cli(capsys, "desktop-install", "--remove", "--color", "never")
    assert code == 0, err
    assert not (data / "applications" / "plcbuilder.desktop").exists()
    assert not (data / "mime" / "packages" / "plcbuilder.xml").exists()
    apps = (config / "mimeapps.list").read_text()
    assert "plcbuilder" not in apps
    assert "text/plain=gedit.desktop;" in apps and "text/x-c=kate.desktop;" in apps
    # twice is fine: nothing left to take away
    assert run_cli(capsys, "desktop-install", "--remove")[0] == 0


def test_a_folder_that_cannot_be_written_is_named(tmp_path, monkeypatch, capsys):
    blocked = tmp_path / "data"
    blocked.write_text("a file where the data folder should be")
    monkeypatch.setenv("XDG_DATA_HOME", str(blocked))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    code, _out, err = run_cli(capsys, "desktop-install", "--color", "never")
    assert code == 1 and "plcbuilder desktop-install: error:" in err and str(blocked) in err

