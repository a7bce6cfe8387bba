"""Includes stay inside the project (issue 17, item 12): ``#include
"/etc/passwd"`` or a link out of the project is an error that says where it
resolved and how to allow it, and the file is never read (its lines are not
echoed in diagnostics). Folders the user names (--include, [build] include)
are allowed."""

from __future__ import annotations

from pathlib import Path

from plcbuilder.api import CompileOptions, Project, compile_file, compile_source

SECRET = "root:x:0:0:secret-line:/root:/bin/bash\n"


def outside_file(tmp_path: Path) -> Path:
    other = tmp_path / "elsewhere"
    other.mkdir()
    f = other / "passwd"
    f.write_text(SECRET)
    return f


def project(tmp_path: Path) -> Path:
    root = tmp_path / "proj"
    (root / "hardware").mkdir(parents=True)
    (root / "include").mkdir()
    (root / "plcbuilder.toml").write_text('name = "p"\n')
    return root


def everything(r) -> str:
    return "\n".join(f"{d.message} {' '.join(d.hints)}" for d in r.diagnostics) + \
        "\n".join(f.text for f in r.sources.files.values())


def test_an_absolute_include_out_of_the_project_is_refused_unread(tmp_path):
    secret = outside_file(tmp_path)
    root = project(tmp_path)
    src = root / "hardware" / "M03.plc"
    src.write_text(f'#include "{secret}"\nmain(){{ exit(99); }};\n')
    r = compile_file(src, Project.open(root).compile_options(src))
    (d,) = [d for d in r.diagnostics if d.is_error]
    assert d.code == "include-outside" and (d.span.line, d.span.col) == (1, 1)
    assert f"'{secret}' resolves to {secret}, outside the project ({root})" in d.message
    assert f"--include {secret.parent}" in d.hints[0] and "[build]" in d.hints[0]
    assert "secret-line" not in everything(r)


def test_relative_and_linked_headers_out_of_the_project(tmp_path):
    secret = outside_file(tmp_path)
    root = project(tmp_path)
    (root / "include" / "pins.h").symlink_to(secret)           # a link in include/
    src = root / "hardware" / "M03.plc"
    src.write_text('#include pins.h\nmain(){ exit(99); };\n')
    r = compile_file(src, Project.open(root).compile_options(src))
    assert [d.code for d in r.errors] == ["include-outside"]
    assert "secret-line" not in everything(r)
    src.write_text('#include "../../elsewhere/passwd"\nmain(){ exit(99); };\n')
    r = compile_file(src, Project.open(root).compile_options(src))
    assert [d.code for d in r.errors] == ["include-outside"]
    (root / "include" / "pins.h").unlink()
    (root / "include").rmdir()
    (root / "include").symlink_to(secret.parent, target_is_directory=True)   # include/ itself
    src.write_text('#include passwd\nmain(){ exit(99); };\n')
    r = compile_file(src, Project.open(root).compile_options(src))
    assert [d.code for d in r.errors] == ["include-outside"]


def test_headers_inside_the_project_still_work(tmp_path):
    root = project(tmp_path)
    (root / "include" / "a.h").write_text("#define A 5\n")
    (root / "include" / "b.h").write_text('#include "../include/a.h"\n#define B A\n')
    (root / "hardware" / "lib.h").symlink_to(root / "include" / "b.h")   # a link inside
    src = root / "hardware" / "M03.plc"
    src.write_text('#include "lib.h"\n#include pins.h\nmain(){ exit(B); };\n')
    r = compile_file(src, Project.open(root).compile_options(src))
    assert r.ok, r.diagnostics


def test_a_folder_named_by_the_user_is_allowed(tmp_path):
    secret = outside_file(tmp_path)
    (secret.parent / "shared.h").write_text("#define SHARED 7\n")
    root = project(tmp_path)
    src = root / "hardware" / "M03.plc"
    src.write_text('#include shared.h\nmain(){ exit(SHARED); };\n')
    opts = Project.open(root).compile_options(src, extra_includes=(secret.parent,))
    assert compile_file(src, opts).ok                                  # --include DIR
    (root / "plcbuilder.toml").write_text('name = "p"\n[build]\ninclude = ["../elsewhere"]\n')
    p = Project.open(root)
    assert p.settings.include == ("../elsewhere",)
    assert compile_file(src, p.compile_options(src)).ok                # [build] include


def test_outside_a_project_the_procedure_folder_is_the_boundary(tmp_path):
    secret = outside_file(tmp_path)
    (tmp_path / "proc").mkdir()
    src = tmp_path / "proc" / "M03.plc"
    src.write_text('#include "../elsewhere/passwd"\nmain(){ exit(99); };\n')
    r = compile_file(src)
    (d,) = r.errors
    assert d.code == "include-outside" and "outside the procedure's folder" in d.message
    assert compile_file(src, CompileOptions(include_dirs=(secret.parent,))).errors[0].code \
        != "include-outside"                 # allowed now: it is read (and is no PLC code)
    r = compile_source('#include "/etc/passwd"\nmain(){ exit(99); };\n', "<input>")
    assert [d.code for d in r.errors] == ["include-not-found"]         # nothing read
