"""Issue 28.6: build/.cache.json is described once, in the cache module's
docstring; the file a build writes has exactly the shape described there."""

import json
import re

from plcbuilder.diagnostics import Diagnostic
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
        assert set(entry) == {"key", "diagnostics", "bin", "bin_stat", "crc32", "size"}
        for row in entry["diagnostics"]:
            Diagnostic.check_dict(row)
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
                "bin", "bin_stat", "crc32", "size", "stat"):
        assert f'"{key}"' in described, key
    assert "[size, mtime_ns, inode]" in described and "trusted" in described
