"""Issue 28.6: build/.cache.json is described once, in the cache module's
docstring; the file a build writes has exactly the shape described there."""

import json
import re
from pathlib import Path

from plcbuilder.diagnostics import Diagnostic
from plcbuilder.lang.builtin_headers import builtin_header
from plcbuilder.project import build_project, create_project
from plcbuilder.project.build import CACHE_FILE, CACHE_VERSION, cache


def test_the_cache_file_is_the_documented_format(tmp_path):
    project = create_project(tmp_path / "proj")
    m05 = project.hardware_dir / "M05.plc"
    m05.write_text(m05.read_text().replace("pwm01=0;", "pwm01=0; unused=3;"))
    r = build_project(project)
    text = (project.build_dir / CACHE_FILE).read_text()
    doc = json.loads(text)
    assert text == json.dumps(doc, sort_keys=True, separators=(",", ":")) + "\n"
    assert set(doc) == {"version", "compiler", "procedures", "files", "image"}
    assert doc["version"] == CACHE_VERSION and doc["compiler"] == cache.compiler_fingerprint()
    assert set(doc["procedures"]) == {f"{p.kind.label}/{p.name}" for p in r.procedures}
    for entry in doc["procedures"].values():
        assert set(entry) == {"key", "diagnostics", "errors", "warnings", "shown", "check",
                              "bin", "bin_stat", "crc32", "size"}
        rows = json.loads(entry["diagnostics"])
        for row in rows:
            Diagnostic.check_dict(row)
        assert entry["errors"] == sum(r["severity"] == 1 for r in rows)
        assert entry["warnings"] == sum(r["severity"] == 2 for r in rows)
        assert entry["check"] == cache._check(entry["diagnostics"], entry["errors"],
                                              entry["warnings"], entry["shown"])
        assert len(entry["bin_stat"]) == 3
    assert doc["procedures"]["hardware/M05"]["diagnostics"]
    assert str(m05) in doc["files"] and str(project.include_dir / "pins.h") in doc["files"]
    for size, mtime_ns, inode, sha, includes, trusted in doc["files"].values():
        assert re.fullmatch(r"[0-9a-f]{64}", sha) and type(trusted) is bool
    assert doc["files"][str(m05)][4] == ["pins.h"]
    assert set(doc["image"]) == {"key", "stat"}
    assert doc["image"]["stat"][0] == project.image_path.stat().st_size


def test_the_docstring_names_every_field():
    described = cache.__doc__
    for key in ("version", "compiler", "procedures", "files", "image", "key", "diagnostics",
                "errors", "warnings", "check", "bin", "bin_stat", "crc32", "shown", "size",
                "stat"):
        assert f'"{key}"' in described, key
    assert "[size, mtime_ns, inode]" in described and "trusted" in described


def _framed(*parts) -> bytes:
    out = b""
    for part in parts:
        b = str(part).encode("utf-8")
        out += len(b).to_bytes(8, "little") + b
    return out


def test_a_procedure_key_is_the_documented_sha256(tmp_path, monkeypatch):
    """The docstring: 'A procedure's key is a SHA-256 of length-prefixed parts: the
    cache version, the compiler fingerprint, the kind, the compile options (strict,
    target, size limit, include folders, root), the source's path, the working
    folder ... and SHA-256; then, following the #include targets breadth first
    ... each target with the folder it is named from and the header found (its
    path and SHA-256, a built-in header's SHA-256, or "missing")'. Worked out here
    from that text for a procedure that includes a project header, which includes
    a built-in one, and a missing one."""
    import hashlib
    monkeypatch.chdir(tmp_path)
    project = create_project(tmp_path / "proj")
    inc = project.include_dir
    (inc / "extra.h").write_text("#include <plc.h>\n#define EXTRA 1\n")
    src = project.hardware_dir / "M05.plc"
    src.write_text('#include "extra.h"\n#include nothere.h\n' + src.read_text())
    build_project(project)
    doc = json.loads((project.build_dir / CACHE_FILE).read_text())
    opts = project.compile_options(src)
    sha = hashlib.sha256
    text = src.read_bytes()
    dirs = [str(d) for d in opts.include_dirs]
    head = _framed(CACHE_VERSION, cache.compiler_fingerprint(), "hardware", opts.strict,
                   opts.target, opts.limit, src, str(tmp_path), sha(text).hexdigest(),
                   opts.root, len(dirs), *dirs)
    # the #include walk, breadth first, as the docstring says
    parts, seen = [], set()
    todo = [(t, str(src.parent)) for t in cache._include_targets(text.decode())]
    assert [t for t, _ in todo[:2]] == ["extra.h", "nothere.h"]
    while todo:
        t, folder = todo.pop(0)
        if (t, folder) in seen:
            continue
        seen.add((t, folder))
        parts += ["include", t, folder]
        where = ([Path(folder)] if folder != "None" else []) + [Path(d) for d in dirs]
        found = next((d / t for d in where if (d / t).is_file()), None)
        if found is not None:
            data = found.read_bytes()
            parts += ["file", found, sha(data).hexdigest()]
            todo += [(n, str(found.parent)) for n in cache._include_targets(data.decode())]
        elif (b := builtin_header(t)) is not None:
            parts += ["builtin", sha(b.encode()).hexdigest()]
            todo += [(n, "None") for n in cache._include_targets(b)]
        else:
            parts += ["missing"]
    assert "builtin" in parts and "missing" in parts and "file" in parts
    key = sha(head + _framed(*parts)).hexdigest()
    assert doc["procedures"]["hardware/M05"]["key"] == key
