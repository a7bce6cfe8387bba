"""Where the IDE keeps its own files (settings.py)."""

from __future__ import annotations

from plcbuilder.ide.settings import SETTINGS_ENV, Settings


def test_the_data_folder_names_the_application_once(tmp_path, monkeypatch):
    """Issue 23 point 14: the example project went to
    ``~/.local/share/PLC Builder/PLC Builder/examples``."""
    monkeypatch.delenv(SETTINGS_ENV, raising=False)
    monkeypatch.delenv("PLCBUILDER_RECOVERY_DIR", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    s = Settings()
    assert s.example_dir() == tmp_path / "data" / "PLC Builder" / "examples"
    assert s.recovery_dir() == tmp_path / "data" / "PLC Builder" / "recovery"


def test_recovery_copies_left_in_the_old_folder_are_still_found(tmp_path, monkeypatch):
    """A crash of an older version left its copies in the doubled folder: they
    are offered, not lost."""
    monkeypatch.delenv(SETTINGS_ENV, raising=False)
    monkeypatch.delenv("PLCBUILDER_RECOVERY_DIR", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    old = tmp_path / "data" / "PLC Builder" / "PLC Builder" / "recovery"
    old.mkdir(parents=True)
    (old / "copy.json").write_text("{}")
    assert Settings().recovery_dir() == old
