"""Build All: outputs, errors, limits, determinism and the incremental cache."""

import json
import shutil

import pytest

from plcbuilder.bytecode.program import Kind, Program
from plcbuilder.image import Limits, read_image, read_romfs
from plcbuilder.project import Project, build_project, create_project
from plcbuilder.project.build import CACHE_FILE

EXAMPLE_HW = ["M02", "M03", "M05", "M07", "M08", "M09", "M71", "M80", "M81", "M84", "OFF"]
EXAMPLE_SW = ["LUBE", "__HANDLER_INIT"]


@pytest.fixture
def example(tmp_path):
    return create_project(tmp_path / "proj")


def small_project(root, files, settings=None):
    root.mkdir(parents=True, exist_ok=True)
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    if settings is not None:
        (root / "plcbuilder.toml").write_text(settings)
    return Project.open(root)


def outputs(project):
    b = project.build_dir
    return {p.name: p.read_bytes() for p in sorted(b.iterdir()) if p.name != CACHE_FILE}


def test_example_project_builds(example):
    calls = []
    r = build_project(example, lambda *a: calls.append(a))
    assert r.ok, [str(d) for d in r.all_diagnostics]
    assert r.all_diagnostics == []                       # not even a warning
    assert [p.name for p in r.procedures] == EXAMPLE_HW + EXAMPLE_SW
    assert calls[0] == (0, 13, "") and calls[-1] == (13, 13, "__HANDLER_INIT")
    assert [c[0] for c in calls] == list(range(14))
    assert r.image_written and r.image_path.exists() and "wrote" in r.image_message
    image = read_image(r.image_path.read_bytes())
    assert image.names(Kind.HARDWARE) == sorted(EXAMPLE_HW)
    assert image.names(Kind.SOFTWARE) == EXAMPLE_SW
    assert image.hw_total == r.hw_total == sum(p.size for p in r.procedures if p.kind is Kind.HARDWARE)
    for pb in r.procedures:
        assert pb.ok and pb.size <= pb.limit
        data = (example.build_dir / f"{pb.name}.bin").read_bytes()
        assert data == pb.binary == image.get(pb.name).data
        assert Program.from_bytes(data).name == pb.name
    assert set(read_romfs(r.image_path.read_bytes()).files()) == \
        {f"{n}.bin" for n in EXAMPLE_HW + EXAMPLE_SW} | {"MANIFEST"}


def test_same_sources_give_identical_outputs(example, tmp_path):
    build_project(example, use_cache=False)
    first = outputs(example)
    build_project(example, use_cache=False)
    assert outputs(example) == first
    # elsewhere, under another name: still the same bytes
    other = tmp_path / "elsewhere" / "copy"
    shutil.copytree(example.root, other, ignore=shutil.ignore_patterns("build"))
    build_project(Project.open(other))
    assert outputs(Project.open(other)) == first


def test_incremental_build_reuses_unchanged_procedures(example):
    r1 = build_project(example)
    first = outputs(example)
    assert (r1.compiled, r1.reused) == (13, 0)
    r2 = build_project(example)
    assert (r2.compiled, r2.reused) == (0, 13)
    assert all(p.cached for p in r2.procedures) and r2.ok and r2.image_written
    assert outputs(example) == first
    # change one procedure: only it is compiled again
    m07 = example.hardware_dir / "M07.plc"
    m07.write_text(m07.read_text().replace("portset(OUTPUT_MIST);", "portset(OUTPUT_MIST);\n  a=1;"))
    r3 = build_project(example)
    assert (r3.compiled, r3.reused) == (1, 12)
    assert not r3.get("M07").cached and r3.get("M03").cached
    assert outputs(example)["M07.bin"] != first["M07.bin"]
    # its warning (a assigned, never read) comes back from the cache next time
    r4 = build_project(example)
    assert r4.compiled == 0 and [d.code for d in r4.get("M07").diagnostics] == \
        [d.code for d in r3.get("M07").diagnostics] != []
    # a fresh build gives the same bytes as the incremental one
    incremental = outputs(example)
    build_project(example, use_cache=False)
    assert outputs(example) == incremental


def test_headers_are_part_of_the_cache_key(example):
    build_project(example)
    pins = example.include_dir / "pins.h"
    pins.write_text(pins.read_text().replace("#define OUTPUT_MIST         2",
                                             "#define OUTPUT_MIST         12"))
    r = build_project(example)
    assert r.compiled == 13                    # every example procedure includes pins.h
    m07 = Program.from_bytes((example.build_dir / "M07.bin").read_bytes())
    fresh = build_project(example, use_cache=False)
    assert fresh.get("M07").binary == m07.to_bytes()
    # a header that shadows include/pins.h (the procedure's folder is searched first)
    (example.hardware_dir / "pins.h").write_text(pins.read_text())
    r = build_project(example)
    assert r.compiled == 11 and r.reused == 2  # the hardware ones


def test_broken_cache_or_missing_binary_is_rebuilt(example):
    build_project(example)
    good = outputs(example)
    (example.build_dir / CACHE_FILE).write_text("{not json")
    r = build_project(example)
    assert r.compiled == 13 and outputs(example) == good
    (example.build_dir / "M03.bin").unlink()
    r = build_project(example)
    assert (r.compiled, r.reused) == (1, 12) and outputs(example) == good
    (example.build_dir / "M05.bin").write_bytes(b"garbage")
    r = build_project(example)
    assert not r.get("M05").cached and outputs(example) == good
    doc = json.loads((example.build_dir / CACHE_FILE).read_text())
    doc["procedures"]["hardware/M08"]["diagnostics"] = [{"severity": "bogus"}]
    (example.build_dir / CACHE_FILE).write_text(json.dumps(doc))
    r = build_project(example)
    assert (r.compiled, r.reused) == (1, 12) and outputs(example) == good


def test_errors_keep_the_previous_image(example):
    r = build_project(example)
    image = example.image_path.read_bytes()
    (example.hardware_dir / "M07.plc").write_text("main() { x = ; }\n")
    (example.software_dir / "BIN.plc").write_bytes(b"\x00\x01binary")
    r = build_project(example)
    assert not r.ok and not r.image_written
    assert "not written" in r.image_message and "previous eeprom.rom is kept" in r.image_message
    assert example.image_path.read_bytes() == image
    assert not r.get("M07").ok and r.get("M07").diagnostics[0].span.line == 1
    assert [d.code for d in r.get("BIN").diagnostics] == ["file-binary"]
    assert not (example.build_dir / "M07.bin").exists()           # no stale binary
    assert (example.build_dir / "M03.bin").exists()               # the others are written
    assert r.get("M03").ok and r.error_count == 2


def test_no_image_yet_is_said(tmp_path):
    p = small_project(tmp_path / "p", {"hardware/M03.plc": "main() { exit(99) }\n"})
    r = build_project(p)
    assert not r.ok and "there is no eeprom.rom yet" in r.image_message
    assert not p.image_path.exists()


def test_removed_procedures_lose_their_binary(example):
    build_project(example)
    (example.hardware_dir / "M09.plc").unlink()
    r = build_project(example)
    assert r.ok and not (example.build_dir / "M09.bin").exists()
    assert "M09" not in read_image(example.image_path.read_bytes()).names()
    (example.hardware_dir / "M08.plc").unlink()
    build_project(example, use_cache=False)
    assert not (example.build_dir / "M08.bin").exists()
    (example.build_dir / "mine.bin").write_bytes(b"not ours")   # never listed: left alone
    build_project(example)
    assert (example.build_dir / "mine.bin").exists()


def test_limits_come_from_the_settings(tmp_path):
    body = "main() { a=1; b=a+2; c=b*a; exit(c); };\n"
    files = {f"hardware/M{i}.plc": body for i in range(10, 14)}
    p = small_project(tmp_path / "p", files, "[limits]\nhw_total = 40\n")
    r = build_project(p)
    size = r.get("M10").size
    assert r.hw_total == 4 * size > 40
    assert not r.ok and not r.image_written
    assert [d.code for d in r.diagnostics] == ["size-limit"]
    assert f"together are {4 * size} bytes of code; the limit is 40" in r.diagnostics[0].message
    p = small_project(tmp_path / "q", files, f"[limits]\nhw_proc = {size - 1}\n")
    r = build_project(p)
    assert not r.ok and all(pb.diagnostics[0].code == "size-limit" for pb in r.procedures)
    assert all(pb.limit == size - 1 for pb in r.procedures)
    p = small_project(tmp_path / "r", files, f"[limits]\nhw_proc = {size}\nhw_total = {4 * size}\n")
    r = build_project(p)
    assert r.ok and read_image(p.image_path.read_bytes()).limits == Limits(size, 4 * size, 16384)


def test_names_must_be_unique_and_valid(tmp_path):
    ok = "main() { exit(99); };\n"
    p = small_project(tmp_path / "p", {"hardware/LUBE.plc": ok, "software/LUBE.plc": ok,
                                       "hardware/bad name.plc": ok, "hardware/M03.plc": ok})
    r = build_project(p)
    codes = {(pb.name, pb.kind): [d.code for d in pb.diagnostics] for pb in r.procedures}
    assert codes[("LUBE", Kind.SOFTWARE)] == ["duplicate-procedure"]
    assert codes[("bad name", Kind.HARDWARE)] == ["procedure-name"]
    assert codes[("M03", Kind.HARDWARE)] == [] and not r.ok


def test_strict_from_settings_or_argument(tmp_path):
    src = {"hardware/M03.plc": "main() { if (eparam) { a=1; } else { a=2; }; exit(a); };\n"}
    p = small_project(tmp_path / "p", src)
    assert build_project(p).ok
    assert not build_project(p, strict=True).ok
    p = small_project(tmp_path / "q", src, "[build]\nstrict = true\n")
    r = build_project(p)
    assert not r.ok and any(d.code == "strict" for d in r.get("M03").diagnostics)
    assert build_project(p, strict=False).ok


def test_source_lines_for_cached_diagnostics(example):
    m05 = example.hardware_dir / "M05.plc"
    m05.write_text(m05.read_text().replace("pwm01=0;", "pwm01=0; unused=3;"))
    r1 = build_project(example)
    r2 = build_project(example)
    d1, d2 = r1.get("M05").diagnostics[0], r2.get("M05").diagnostics[0]
    assert d1 == d2 and r2.get("M05").cached
    assert r2.get("M05").source_line(d2.span.file, d2.span.line) == \
        r1.get("M05").source_line(d1.span.file, d1.span.line)
    assert "unused=3" in r2.get("M05").source_line(d2.span.file, d2.span.line)


def test_empty_project_builds_an_empty_image(tmp_path):
    """A project with no procedure yet (its settings file only) builds an empty
    image; a folder with nothing at all is no project (below)."""
    p = small_project(tmp_path / "empty", {}, 'name = "empty"\n')
    r = build_project(p)
    assert r.ok and r.image_written and read_image(p.image_path.read_bytes()).procedures == ()


# ------------------------------------- links out of the project (issue 17, item 12)

def _linked_project(tmp_path):
    other = tmp_path / "elsewhere"
    other.mkdir()
    (other / "passwd").write_text("root:x:0:0:secret-line:/root:/bin/bash\n")
    root = tmp_path / "proj"
    (root / "hardware").mkdir(parents=True)
    (root / "hardware" / "M03.plc").write_text("main(){ exit(99); };\n")
    return root, other


def test_a_source_linked_out_of_the_project_is_refused_unread(tmp_path):
    root, other = _linked_project(tmp_path)
    (root / "hardware" / "M04.plc").symlink_to(other / "passwd")
    r = build_project(Project.open(root))
    assert not r.ok and not r.image_written
    (d,) = r.get("M04").diagnostics
    assert d.code == "source-outside-project" and str(other / "passwd") in d.message
    assert d.span is None              # no span: rendering shows none of the file's lines
    from plcbuilder.diagnostics import render_text
    assert "secret-line" not in render_text(d, r.source_line)
    assert r.get("M03").ok


def test_a_source_folder_linked_out_of_the_project_is_refused_and_one_linked_inside_is_not(tmp_path):
    """A whole software/ that is a link out of the project: each of its
    procedures is refused unread; a link to a folder inside the project builds."""
    root, other = _linked_project(tmp_path)
    (other / "P1.plc").write_text("main(){ exit(99); };\n")
    (root / "software").symlink_to(other, target_is_directory=True)
    r = build_project(Project.open(root))
    assert not r.ok
    (d,) = r.get("P1").diagnostics
    assert d.code == "source-outside-project" and str(other / "P1.plc") in d.message
    (root / "software").unlink()
    (root / "lib").mkdir()
    (root / "lib" / "P1.plc").write_text("main(){ exit(99); };\n")
    (root / "software").symlink_to(root / "lib", target_is_directory=True)
    r = build_project(Project.open(root))
    assert r.ok and r.get("P1").ok and r.get("M03").ok


def test_a_build_folder_linked_out_of_the_project_is_refused(tmp_path):
    root, other = _linked_project(tmp_path)
    (root / "build").symlink_to(other, target_is_directory=True)
    r = build_project(Project.open(root))
    assert not r.ok and not r.image_written
    (d,) = r.diagnostics
    assert d.code == "build-outside-project" and str(other) in d.message
    assert sorted(p.name for p in other.iterdir()) == ["passwd"]        # nothing written there
    assert "outside the project" in r.image_message

# ------------------------------------- issue 17.11: a killed build's temporary files

KILLED_BUILD = """
import os, sys
from plcbuilder.project import Project, build_project
real = os.replace
def die(src, dst):           # killed between writing a temporary file and renaming it
    if os.path.basename(dst) == sys.argv[2]:
        os._exit(9)
    real(src, dst)
os.replace = die
build_project(Project.open(sys.argv[1]), use_cache=False)
"""


@pytest.mark.parametrize("victim", ["M05.bin", "eeprom.rom", CACHE_FILE])
def test_a_killed_builds_temporary_files_are_removed_next_time(example, victim):
    import os
    import subprocess
    import sys
    build_project(example)
    (example.build_dir / victim).unlink()          # so that the build writes it again
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    rc = subprocess.run([sys.executable, "-c", KILLED_BUILD, str(example.root), victim],
                        env=env).returncode
    assert rc == 9
    left = [p.name for p in example.build_dir.iterdir() if p.name.endswith(".tmp")]
    assert len(left) == 1 and left[0].startswith(f".{victim}.")    # what the kill left
    # files that only look alike are not ours: they stay
    others = [".M03.bin.tmp", "notes.tmp", ".M03.bin.DEADBEEF.tmp", ".M03.bin.0123abcd.tmp.keep"]
    for name in others:
        (example.build_dir / name).write_text("mine")
    (example.build_dir / ".dir.0123abcd.tmp").mkdir()
    r = build_project(example)
    assert r.ok
    names = {p.name for p in example.build_dir.iterdir()}
    assert not names & set(left)
    assert set(others) | {".dir.0123abcd.tmp"} <= names


# ------------------------------------------- issue 14.2: parallel, incremental, small

def test_worker_processes_give_the_same_build(example, tmp_path):
    """Compiling in worker processes gives the same files and the same results."""
    other = tmp_path / "other"
    shutil.copytree(example.root, other)
    serial = build_project(example, jobs=1)
    parallel = build_project(Project.open(other), jobs=2)
    assert outputs(example) == outputs(Project.open(other))
    strip = lambda r: [(p.name, p.kind, p.size, p.crc32, p.binary, [(d.code, d.message) for d in
                        p.diagnostics]) for p in r.procedures]  # noqa: E731
    assert strip(serial) == strip(parallel) and parallel.compiled == 13


def test_unchanged_rebuild_reads_no_source(example, monkeypatch):
    import os
    import pathlib
    old = 1_600_000_000
    for p in list(example.root.rglob("*.plc")) + list(example.root.rglob("*.h")):
        os.utime(p, (old, old))
    build_project(example)
    real = pathlib.Path.read_bytes

    def guarded(self):
        assert self.suffix not in (".plc", ".h", ".bin"), f"read {self}"
        return real(self)
    monkeypatch.setattr(pathlib.Path, "read_bytes", guarded)
    from plcbuilder.project.build import cache, pool, results
    real_bounded = cache.read_bounded

    def guarded_bounded(path, *args, **kw):
        assert pathlib.Path(path).suffix not in (".plc", ".h", ".bin"), f"read {path}"
        return real_bounded(path, *args, **kw)
    for module in (cache, pool, results):             # every reader of build's files
        monkeypatch.setattr(module, "read_bounded", guarded_bounded)
    r = build_project(example)
    assert (r.compiled, r.reused) == (0, 13) and r.ok and "up to date" in r.image_message


def test_a_same_size_edit_within_the_timestamp_is_seen(example):
    """A file modified just before a build is read again by the next one, even
    when its size and modification time did not change (racy timestamps)."""
    import os
    build_project(example)
    m03 = example.hardware_dir / "M03.plc"
    st = m03.stat()
    text = m03.read_text()
    m03.write_text(text.replace("exit(", "exit( ", 1).replace("  ", " ", 1))
    assert m03.stat().st_size == st.st_size
    os.utime(m03, ns=(st.st_atime_ns, st.st_mtime_ns))
    r = build_project(example)
    assert r.compiled == 1 and not r.get("M03").cached


def test_results_keep_only_what_the_report_needs(example):
    import pickle
    m05 = example.hardware_dir / "M05.plc"
    m05.write_text(m05.read_text().replace("pwm01=0;", "pwm01=0; unused=3;"))
    r = build_project(example)
    pb = r.get("M05")
    assert pb.diagnostics and all((d.span.file, d.span.line) in pb.lines for d in pb.diagnostics)
    assert "unused=3" in r.source_line(pb.diagnostics[0].span.file, pb.diagnostics[0].span.line)
    assert not hasattr(pb, "_source_line")             # no CompileResult held
    assert len(pickle.dumps(r.procedures)) < 1500 * len(r.procedures)


def test_builds_keep_no_binary_bytes_in_memory(example):
    """Each ProcedureBuild keeps name, size and CRC; its bytes are read back from build/."""
    import zlib
    for r in (build_project(example), build_project(example)):   # compiled, then cached
        assert r.ok and r.image_written
        image = read_image(example.image_path.read_bytes())
        for pb in r.procedures:
            assert pb._binary is None
            assert pb.binary == (example.build_dir / pb.bin_name).read_bytes()
            assert zlib.crc32(pb.binary) == pb.crc32 == image.get(pb.name).crc32
            assert pb.program().name == pb.name


def test_the_image_of_binaries_compiled_now_is_made_without_decoding_them_again(example,
                                                                               monkeypatch):
    """A cold Build All spent a tenth of its time decoding its own binaries again
    for the image: those it compiled now go in on their CRC and code size; the
    image is the one a full check makes, and a cached binary is still decoded."""
    from plcbuilder.image import manifest, write_image
    loads = []
    real = manifest._load
    monkeypatch.setattr(manifest, "_load", lambda n, k, d: loads.append(n) or real(n, k, d))
    r = build_project(example)
    assert r.ok and r.image_written and loads == []
    binaries = [(pb.name, pb.kind, pb.binary) for pb in r.procedures]
    for pb in r.procedures:
        assert pb.size == Program.from_bytes(pb.binary).code_size
    assert example.image_path.read_bytes() == write_image(binaries)     # (this one decodes)
    loads.clear()
    (example.hardware_dir / "M05.plc").write_text(
        (example.hardware_dir / "M05.plc").read_text() + "\n")
    example.image_path.unlink()
    r = build_project(example)
    assert r.image_written and not r.get("M05").cached
    assert sorted(loads) == sorted(pb.name for pb in r.procedures if pb.cached)


def test_a_binary_changed_after_compiling_does_not_go_into_the_image(example, monkeypatch):
    """The image is made from build/'s binaries as compiled, or not at all."""
    from plcbuilder.project.build import steps
    real = steps.iter_image

    def tampered(programs, *args):
        (example.build_dir / "M03.bin").write_bytes(b"changed")
        return real(programs, *args)

    monkeypatch.setattr(steps, "iter_image", tampered)
    r = build_project(example)
    assert not r.image_written
    assert any("build/M03.bin changed during the build" in d.message for d in r.diagnostics)
    assert not example.image_path.exists()


def test_a_source_changed_while_it_is_built_is_not_cached_under_its_old_key(example, monkeypatch):
    """The compiler reads each source itself (Build All holds no project's
    sources): when it reads other bytes than the cache key hashed, the result
    is reported but not cached, so going back to the old text compiles again."""
    from plcbuilder.project.build import cache, pool
    m05 = example.hardware_dir / "M05.plc"
    original = m05.read_text()
    edited = original.replace("pwm01=0;", "pwm01=0; unused=3;")
    real = cache.read_bounded
    reads = []

    def edit_first(path, *args, **kw):
        if str(path) == str(m05):
            reads.append(path)
            if len(reads) == 2:             # the compiler's read: after its key was made
                m05.write_text(edited)
        return real(path, *args, **kw)
    for module in (cache, pool):                # the key's read, then the compiler's
        monkeypatch.setattr(module, "read_bounded", edit_first)
    r = build_project(example, jobs=1)
    assert any(d.code == "unused-variable" or "unused" in d.message for d in r.get("M05").diagnostics)
    for module in (cache, pool):
        monkeypatch.setattr(module, "read_bounded", real)
    m05.write_text(original)
    again = build_project(example, jobs=1)
    assert not again.get("M05").cached and again.get("M05").warnings == 0
    assert again.get("M03").cached


def test_counts_and_packed_diagnostics_agree(example):
    m05 = example.hardware_dir / "M05.plc"
    m05.write_text(m05.read_text().replace("pwm01=0;", "pwm01=0; unused=3; x = 1 / 0;"))
    for r in (build_project(example), build_project(example)):     # compiled, then cached
        for pb in r.procedures:
            ds = pb.diagnostics
            assert pb.errors == sum(d.is_error for d in ds)
            assert pb.warnings == sum(d.severity == 2 for d in ds)
        assert r.error_count == sum(d.is_error for d in r.all_diagnostics)
        assert r.warning_count == len(r.all_diagnostics) - r.error_count


@pytest.mark.parametrize("row", [
    {"severity": 2, "code": "x", "message": "m", "span": ["f", 1, 1, 1], "hints": [],
     "related": []},
    {"severity": 2, "code": "x", "message": "m", "span": None, "hints": [3], "related": []},
    {"severity": 2, "code": "x", "message": "m", "span": None, "hints": [],
     "related": [[None]]},
    {"severity": 9, "code": "x", "message": "m", "span": None, "hints": [], "related": []},
    {"severity": 2, "code": None, "message": "m", "span": None, "hints": [], "related": []},
    "not a row"])
def test_a_damaged_diagnostic_in_the_cache_compiles_again(example, row):
    """A cached procedure's diagnostics are checked when read (and decoded only
    when asked for): a damaged one makes that procedure compile again."""
    build_project(example)
    doc = json.loads((example.build_dir / CACHE_FILE).read_text())
    for damaged in ([row], json.dumps([row])):       # not text; text its check does not match
        doc["procedures"]["hardware/M08"]["diagnostics"] = damaged
        (example.build_dir / CACHE_FILE).write_text(json.dumps(doc))
        r = build_project(example)
        assert (r.compiled, r.reused) == (1, 12) and not r.get("M08").cached
        assert all(isinstance(pb.diagnostics, list) for pb in r.procedures)


def test_diagnostics_text_that_passes_its_check_but_is_no_diagnostics_is_one_error(example):
    """An entry made to pass its check (its CRC worked out again) with text that
    does not decode to diagnostics: asking for them gives one error naming the
    cache and what to do, never an exception."""
    from plcbuilder.project.build import cache
    build_project(example)
    doc = json.loads((example.build_dir / CACHE_FILE).read_text())
    for text in ('[{"severity": 2}]', "[" * 100_000, "{}", "not json"):
        entry = doc["procedures"]["hardware/M08"]
        entry["diagnostics"] = text
        entry["check"] = cache._check(text, entry["errors"], entry["warnings"], entry["shown"])
        (example.build_dir / CACHE_FILE).write_text(json.dumps(doc))
        r = build_project(example)
        assert r.get("M08").cached
        (d,) = r.get("M08").diagnostics
        assert d.code == "build-cache" and "build/.cache.json" in d.message \
            and "--no-cache" in d.hints[0]


def test_a_folder_that_is_not_a_project_is_not_built(tmp_path):
    """Issue 24.5: Build All wrote build/eeprom.rom into any folder. Whoever
    calls build_project (the CLI, the IDE, the debug adapter) gets one error
    and nothing is written there."""
    stray = tmp_path / "stray"
    stray.mkdir()
    (stray / "notes.txt").write_text("x\n")
    result = build_project(Project.open(stray))
    assert not result.ok and not result.image_written and result.procedures == []
    assert [d.code for d in result.diagnostics] == ["not-a-project"]
    assert "not a project: it has no plcbuilder.toml, hardware/ or software/" in \
        result.diagnostics[0].message
    assert sorted(p.name for p in stray.iterdir()) == ["notes.txt"]
