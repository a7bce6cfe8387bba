"""plcbuilder new DIR."""

from plcbuilder.cli.main import main


def test_new_then_build(tmp_path, capsys):
    dest = tmp_path / "table"
    assert main(["new", str(dest)]) == 0
    out = capsys.readouterr().out
    assert f"created project 'table' in {dest}" in out
    assert "M03" in out and "__HANDLER_INIT" in out and f"plcbuilder build {dest}" in out
    assert (dest / "plcbuilder.toml").is_file() and (dest / "include" / "pins.h").is_file()
    assert main(["build", str(dest), "-q"]) == 0


def test_new_with_a_name(tmp_path, capsys):
    assert main(["new", str(tmp_path / "x"), "--name", "Plasma"]) == 0
    assert "created project 'Plasma'" in capsys.readouterr().out
    assert 'name = "Plasma"' in (tmp_path / "x" / "plcbuilder.toml").read_text()


def test_new_refuses_a_folder_in_use(tmp_path, capsys):
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "file").write_text("x")
    assert main(["new", str(tmp_path / "used")]) == 1
    assert "not empty" in capsys.readouterr().err
    assert [p.name for p in (tmp_path / "used").iterdir()] == ["file"]
