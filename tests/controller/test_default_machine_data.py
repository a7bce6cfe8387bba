"""Issue 26.1: the default machine is read without tomllib at start-up, from
``controller/default_machine_data.py``; that copy must be what tomllib reads
from ``resources/machine/default.toml``, and a stale copy is never used."""

import tomllib

from plcbuilder.controller import default_machine_data, machine_config

REGENERATE = ("run `.venv/bin/python -m plcbuilder.controller.machine_config` and commit "
              "plcbuilder/controller/default_machine_data.py")


def test_the_kept_copy_is_the_default_machine_file_as_tomllib_reads_it():
    text = machine_config.default_machine_text()
    assert default_machine_data.TEXT == text, \
        f"resources/machine/default.toml changed since its copy was made: {REGENERATE}"
    assert default_machine_data.DATA == tomllib.loads(text)
    assert machine_config.default_machine_data_source() == \
        open(default_machine_data.__file__, encoding="utf-8").read(), REGENERATE


def test_the_default_machine_is_the_same_from_the_copy_or_the_file():
    text = machine_config.default_machine_text()
    assert machine_config.parse_machine(text, "<default machine>", default_machine_data.DATA) \
        == machine_config.parse_machine(text, "<default machine>")


def test_a_stale_copy_is_not_used(monkeypatch):
    monkeypatch.setattr(default_machine_data, "TEXT", "name = 'an older machine'\n")
    monkeypatch.setattr(default_machine_data, "DATA", {"name": "an older machine"})
    monkeypatch.setattr(machine_config, "_default_cache", None)
    m = machine_config.default_machine()
    assert m.name != "an older machine"
    monkeypatch.setattr(machine_config, "_default_cache", None)
