"""eeprom.rom: write_image / read_image and the manifest."""

import json
import os
import subprocess
import zlib

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.image import ImageError, Limits, read_image, read_romfs, write_image, write_romfs
from plcbuilder.image.manifest import MANIFEST_NAME, manifest_text


def entries_of(programs):
    from plcbuilder.bytecode.program import Program
    out = []
    for name, kind, data in sorted(programs):
        out.append({"name": name, "kind": Kind(kind).label, "file": name + ".bin",
                    "code_size": Program.from_bytes(data).code_size, "file_size": len(data),
                    "crc32": f"{zlib.crc32(data):08x}"})
    return out


def forge(files, entries, limits=Limits(), volume="plcbuilder"):
    """An image whose ROMFS layer is valid, with whatever manifest we like."""
    files = dict(files)
    if entries is not None:
        files[MANIFEST_NAME] = manifest_text(entries, limits)
    return write_romfs(files, volume)


def files_of(programs):
    return {name + ".bin": data for name, _k, data in programs}


def test_round_trip(sample_programs):
    img = write_image(sample_programs)
    assert len(img) % 1024 == 0
    image = read_image(img)
    assert [p.name for p in image.procedures] == sorted(n for n, _k, _d in sample_programs)
    by = {n: (k, d) for n, k, d in sample_programs}
    for p in image.procedures:
        kind, data = by[p.name]
        assert p.kind is kind and p.data == data and p.crc32 == zlib.crc32(data)
        assert p.program.code_size == p.code_size and p.file_size == len(data)
    assert image.hw_total == 120 + 40 + 480 + 60
    assert image.names(Kind.SOFTWARE) == ["LUBE", "__HANDLER_INIT"]
    assert image.limits == image.built_for == Limits()
    names = set(read_romfs(img).files())
    assert names == {n + ".bin" for n, _k, _d in sample_programs} | {"MANIFEST"}


def test_deterministic(sample_programs):
    assert write_image(sample_programs) == write_image(list(reversed(sample_programs)))
    assert write_image([(n, k.label, d) for n, k, d in sample_programs]) == write_image(sample_programs)


def test_manifest_is_readable_json(sample_programs):
    raw = read_romfs(write_image(sample_programs)).files()["MANIFEST"]
    doc = json.loads(raw)
    assert doc["format"] == "plcbuilder-image" and doc["version"] == 2
    assert doc["limits"] == {"hw_proc": 512, "hw_total": 8192, "sw_proc": 16384}
    m03 = [e for e in doc["procedures"] if e["name"] == "M03"][0]
    assert m03["kind"] == "hardware" and m03["code_size"] == 120 and m03["file"] == "M03.bin"
    assert len(raw.splitlines()) == 3 + len(doc["procedures"])    # one procedure a line


def test_empty_image():
    image = read_image(write_image([]))
    assert image.procedures == () and image.hw_total == 0


def test_image_from_genromfs_reads_the_same(sample_programs, genromfs, tmp_path):
    ours = write_image(sample_programs)
    folder = tmp_path / "img"
    folder.mkdir()
    for name, data in read_romfs(ours).files().items():
        (folder / name).write_bytes(data)
        os.chmod(folder / name, 0o644)
    out = tmp_path / "eeprom.rom"
    subprocess.run([genromfs, "-f", str(out), "-d", str(folder), "-V", "plcbuilder"], check=True)
    theirs = read_image(out.read_bytes())
    assert read_image(ours) == theirs


# ------------------------------------------------------------ write refusals

def test_write_refuses_what_the_controller_would(make_program):
    big = make_program("M80", Kind.HARDWARE, 513)
    with pytest.raises(ImageError, match=r"procedure M80 \(hardware\): code is 513 bytes"):
        write_image([("M80", Kind.HARDWARE, big)])
    assert read_image(write_image([("M80", Kind.HARDWARE, big)], Limits(hw_proc=600)),
                      Limits(hw_proc=600)).get("M80").code_size == 513
    many = [(f"M{i}", Kind.HARDWARE, make_program(f"M{i}", Kind.HARDWARE, 500)) for i in range(17)]
    with pytest.raises(ImageError, match=r"together are 8500 bytes, over the 8192-byte limit"):
        write_image(many)
    with pytest.raises(ImageError, match="cannot go into an image"):
        write_image([("a b", Kind.HARDWARE, make_program("x", Kind.HARDWARE))])
    p = make_program("M03", Kind.HARDWARE)
    with pytest.raises(ImageError, match="given twice"):
        write_image([("M03", Kind.HARDWARE, p), ("M03", Kind.HARDWARE, p)])
    with pytest.raises(ImageError, match="procedure M03: M03.bin does not load"):
        write_image([("M03", Kind.HARDWARE, p[:-1])])
    with pytest.raises(ImageError, match="manifest says software, M03.bin is a hardware"):
        write_image([("M03", "software", p)])
    with pytest.raises(ImageError, match="unknown kind"):
        write_image([("M03", "firmware", p)])
    with pytest.raises(ImageError, match="limit hw_proc"):
        write_image([], Limits(hw_proc=0))


def test_software_limit(make_program):
    big = make_program("BIG", Kind.SOFTWARE, 16385)
    with pytest.raises(ImageError, match=r"BIG \(software\): code is 16385 bytes, over the 16384"):
        write_image([("BIG", Kind.SOFTWARE, big)])


# ------------------------------------------------------------- read refusals

def test_manifest_lies_are_refused(sample_programs, make_program):
    files = files_of(sample_programs)
    good = entries_of(sample_programs)
    assert read_image(forge(files, good))          # the forge itself is sound

    def lie(**change):
        name = change.pop("who", "M03")
        out = [dict(e) for e in good]
        for e in out:
            if e["name"] == name:
                e.update(change)
        return out

    cases = [
        (forge(files, None), "no MANIFEST"),
        (forge(files, lie(crc32="00000000")), "procedure M03: CRC-32 of M03.bin is"),
        (forge(files, lie(file_size=5)), "procedure M03: M03.bin is .* bytes, the manifest says 5"),
        (forge(files, lie(code_size=7)), "procedure M03: code is 120 bytes, the manifest says 7"),
        (forge(files, lie(kind="software")), "procedure M03: the manifest says software"),
        (forge(files, lie(file="M04.bin")), "procedure M03: file is 'M04.bin'"),
        (forge(files, [e for e in good if e["name"] != "M05"]), "'M05.bin' .* is not in the manifest"),
        (forge({k: v for k, v in files.items() if k != "OFF.bin"}, good),
         "procedure OFF: the manifest lists OFF.bin, the image has no such file"),
        (forge({**files, "M03.bin": files["M05.bin"]}, good), "procedure M03"),
        (forge({**files, "junk": {"x": b"1"}}, good), "unexpected directory 'junk'"),
        (forge(files, good[:1] + good), "listed twice"),
        (forge(files, good, volume="other"), "volume name"),
        (forge(files, good, Limits(hw_proc=100)), r"procedure M03 \(hardware\): code is 120 bytes"),
        (forge(files, good, Limits(hw_total=600)), "together are 700 bytes"),
    ]
    bad_m03 = bytearray(files["M03.bin"])
    bad_m03[30] ^= 0xFF
    fixed = lie(crc32=f"{zlib.crc32(bytes(bad_m03)):08x}")
    cases.append((forge({**files, "M03.bin": bytes(bad_m03)}, fixed), "procedure M03: M03.bin does not load"))
    for img, why in cases:
        with pytest.raises(ImageError, match=why):
            read_image(img)


@pytest.mark.parametrize("text, why", [
    (b"\xff\xfe", "not UTF-8"),
    (b"{", "not valid JSON"),
    (b"[]", "expected a JSON object"),
    (b'{"format": "plcbuilder-image", "version": 2, "limits": {}, "procedures": [], "x": 1}',
     "unexpected keys"),
    (b'{"format": "other", "version": 1, "limits": {}, "procedures": []}', "format is 'other'"),
    (b'{"format": "plcbuilder-image", "version": 3, "limits": {}, "procedures": []}',
     "format version 3"),
    (b'{"format": "plcbuilder-image", "version": 1, "limits": {}, "procedures": []}',
     "format version 1, this reader reads version 2"),
    (b'{"format": "plcbuilder-image", "version": 1, "limits": {"hw_proc": NaN, "hw_total": 1,'
     b' "sw_proc": 1}, "procedures": []}', "not valid JSON"),
    (b'{"format": "plcbuilder-image", "version": 2, "version": 2, "limits": {}, "procedures": []}',
     "appears twice"),
    (b'{"format": "plcbuilder-image", "version": 2, "manifest_crc32": "00000000", "limits": {"hw_proc": true, "hw_total": 1,'
     b' "sw_proc": 1}, "procedures": []}', "limits.hw_proc"),
    (b'{"format": "plcbuilder-image", "version": 2, "manifest_crc32": "00000000", "limits": {"hw_proc": 1, "hw_total": 1,'
     b' "sw_proc": 1}, "procedures": [{"name": "M03"}]}', "procedure M03: missing keys"),
    (b"[" * 100000 + b"]" * 100000, "not valid JSON|more than"),
])
def test_bad_manifests(text, why):
    with pytest.raises(ImageError, match=why):
        read_image(write_romfs({"MANIFEST": text}, "plcbuilder"))


def test_manifest_must_be_canonical(sample_programs):
    files = files_of(sample_programs)
    raw = manifest_text(entries_of(sample_programs), Limits())
    for variant in (raw.replace(b'"kind"', b'"\\u006bind"', 1),
                    raw.replace(b", ", b",\t", 1),
                    raw + b"\n"):
        assert json.loads(variant) == json.loads(raw)
        with pytest.raises(ImageError, match="canonical"):
            read_image(write_romfs({**files, "MANIFEST": variant}, "plcbuilder"))


def test_controller_limits_override_the_manifest(make_program):
    img = write_image([("M80", Kind.HARDWARE, make_program("M80", Kind.HARDWARE, 700))],
                      Limits(hw_proc=1024))
    assert read_image(img).get("M80").code_size == 700
    with pytest.raises(ImageError, match=r"M80 \(hardware\): code is 700 bytes, over the 512"):
        read_image(img, Limits())


def test_read_image_refuses_non_bytes():
    with pytest.raises(ImageError):
        read_image("not bytes")


# ------------------------------------------- issue 17.9: the manifest is checked

def test_one_bit_in_the_manifest_limits_is_refused(sample_programs):
    """17.9: "hw_proc": 512 -> 532 (one bit) was accepted: the limits were
    covered by no checksum. The manifest's own CRC-32 refuses it now."""
    files = read_romfs(write_image(sample_programs)).files()
    raw = files[MANIFEST_NAME]
    flipped = raw.replace(b'"hw_proc": 512', b'"hw_proc": 532')
    assert flipped != raw and bin(int.from_bytes(raw, "big") ^ int.from_bytes(flipped, "big")).count("1") == 1
    with pytest.raises(ImageError, match=r"manifest: its CRC-32 is [0-9a-f]{8}, it says"):
        read_image(write_romfs({**files, MANIFEST_NAME: flipped}, "plcbuilder"))


def test_every_single_bit_flip_of_the_manifest_is_refused(sample_programs):
    files = read_romfs(write_image(sample_programs)).files()
    raw = files[MANIFEST_NAME]
    for bit in range(len(raw) * 8):
        buf = bytearray(raw)
        buf[bit // 8] ^= 1 << (bit % 8)
        with pytest.raises(ImageError):
            read_image(write_romfs({**files, MANIFEST_NAME: bytes(buf)}, "plcbuilder"))


def test_manifest_crc_is_of_its_own_bytes(sample_programs):
    raw = read_romfs(write_image(sample_programs)).files()[MANIFEST_NAME]
    own = json.loads(raw)["manifest_crc32"]
    assert f"{zlib.crc32(raw.replace(own.encode(), b'00000000', 1)):08x}" == own


def test_procedures_out_of_name_order_are_refused(sample_programs):
    """17.9: a manifest listing procedures out of name order was accepted (its
    text was regenerated in the order it came); only the canonical form is."""
    files = files_of(sample_programs)
    good = entries_of(sample_programs)
    assert read_image(forge(files, good))
    swapped = [good[1], good[0]] + good[2:]
    with pytest.raises(ImageError, match="must be in name order"):
        read_image(forge(files, swapped))
    with pytest.raises(ImageError, match="must be in name order"):
        read_image(forge(files, list(reversed(good))))


def test_the_documented_maximum_of_procedures_fits(make_program):
    """17.9: 4,096 procedures is the documented maximum, but the 256 KiB manifest
    limit refused an image at ~2,200. Now exactly 4,096 (with the longest names)
    is written and read back, and 4,097 is refused by the writer and the reader."""
    from plcbuilder.image.manifest import MAX_MANIFEST, MAX_PROCEDURES
    assert MAX_PROCEDURES == 4096
    def named(i):
        name = f"{i:05d}".ljust(64, "p")
        return name, Kind.SOFTWARE, make_program(name, Kind.SOFTWARE, 3)
    progs = [named(i) for i in range(4096)]
    image = write_image(progs)
    assert len(read_image(image).procedures) == 4096
    assert len(read_romfs(image).files()[MANIFEST_NAME]) <= MAX_MANIFEST
    with pytest.raises(ImageError, match="4097 procedures, at most 4096"):
        write_image(progs + [named(4096)])
    files = read_romfs(image).files()
    extra = named(4096)
    files[extra[0] + ".bin"] = extra[2]
    entries = entries_of(progs + [extra])
    with pytest.raises(ImageError, match="manifest lists 4097 procedures, at most 4096"):
        read_image(forge(files, entries))


def test_binaries_given_as_readers_make_the_same_image(sample_programs):
    """iter_image reads each binary to check it and again to write it, keeping none."""
    from plcbuilder.image.manifest import iter_image
    reads = []

    def reader(name, data):
        def read():
            reads.append(name)
            return data
        return read

    lazy = [(n, k, reader(n, d)) for n, k, d in sample_programs]
    chunks = iter_image(lazy)
    assert sorted(reads) == sorted(n for n, _k, _d in sample_programs)   # all checked first
    assert b"".join(chunks) == write_image(sample_programs)
    assert len(reads) == 2 * len(sample_programs)


def test_a_binary_that_changes_between_check_and_write_is_refused(sample_programs):
    from plcbuilder.image.manifest import iter_image
    name, kind, data = sample_programs[0]
    answers = iter([data, data[:-1] + bytes([data[-1] ^ 1])])    # one bit flipped
    lazy = [(name, kind, lambda: next(answers))]
    with pytest.raises(ImageError, match=f"{name}.bin changed while the image was written"):
        b"".join(iter_image(lazy))


def test_checked_binaries_are_taken_on_their_crc_others_are_loaded(sample_programs):
    """iter_image's ``checked``: a binary of that name, kind and CRC goes in on
    the code size given; a CRC or kind that differs is loaded and checked."""
    from plcbuilder.image.manifest import iter_image
    name, kind, data = sample_programs[0]
    full = write_image(sample_programs)
    size = read_image(full).get(name).code_size
    ok = {name: (Kind(kind), zlib.crc32(data), size)}
    assert b"".join(iter_image(sample_programs, None, ok)) == full
    broken = [(name, kind, data[:20])] + list(sample_programs[1:])          # cut short
    with pytest.raises(ImageError, match=f"procedure {name}: {name}.bin does not load"):
        b"".join(iter_image(broken, None, ok))                               # CRC differs
    other = Kind.SOFTWARE if Kind(kind) is Kind.HARDWARE else Kind.HARDWARE
    with pytest.raises(ImageError, match="the manifest says"):
        b"".join(iter_image([(name, other, data)], None, ok))                # kind differs
