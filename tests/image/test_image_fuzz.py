"""Thousands of damaged or forged images: every one is refused with ImageError
(and never any other exception)."""

import json
import random
import struct

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.image import ImageError, Limits, read_image, read_romfs, write_image, write_romfs
from plcbuilder.image.manifest import MANIFEST_NAME, manifest_text


def refused(data, limits=None):
    try:
        read_image(data, limits)
    except ImageError as exc:
        assert str(exc)
        return True
    return False


def sum32(buf, start, end):
    return sum(struct.unpack_from(f">{(end - start) // 4}I", buf, start)) & 0xFFFFFFFF


def header_spans(img):
    fs = read_romfs(img)
    return [(c.offset, c.offset + 16 + (len(c.name.encode()) + 16) // 16 * 16)
            for c in fs.root.children]


def refix(buf, spans):
    buf = bytearray(buf)
    for off, end in spans:
        struct.pack_into(">I", buf, off + 12, 0)
        struct.pack_into(">I", buf, off + 12, -sum32(buf, off, end) & 0xFFFFFFFF)
    size = struct.unpack_from(">I", buf, 8)[0]
    span = min(512, size, len(buf) // 16 * 16)
    struct.pack_into(">I", buf, 12, 0)
    struct.pack_into(">I", buf, 12, -sum32(buf, 0, span) & 0xFFFFFFFF)
    return bytes(buf)


@pytest.fixture
def image(sample_programs):
    img = write_image(sample_programs)
    assert len(img) >= 2048 and read_image(img)
    return img


def test_every_single_byte_flip_is_refused(image):
    rng = random.Random(1)
    failures = [i for i in range(len(image))
                if not refused(image[:i] + bytes([image[i] ^ rng.randrange(1, 256)]) + image[i + 1:])]
    assert failures == []
    assert len(image) >= 1000


def test_random_multi_byte_damage_is_refused(image):
    rng = random.Random(2)
    for _ in range(400):
        buf = bytearray(image)
        for _ in range(rng.randint(2, 12)):
            buf[rng.randrange(len(buf))] ^= rng.randrange(1, 256)
        if bytes(buf) != image:
            assert refused(bytes(buf))
        # a run of garbage
        start = rng.randrange(len(image) - 64)
        junk = bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
        buf = image[:start] + junk + image[start + len(junk):]
        if buf != image:
            assert refused(buf)


def test_truncated_or_extended_images_are_refused(image):
    rng = random.Random(3)
    lengths = set(range(0, 64)) | {rng.randrange(len(image)) for _ in range(300)} | {len(image) - 1}
    for n in sorted(lengths):
        assert refused(image[:n]), n
    for extra in (b"\0", b"\0" * 16, b"\0" * 1024, b"x"):
        assert refused(image + extra)


def test_structural_tampering_with_repaired_checksums_is_refused(image):
    """Bypass the checksums: change a header field, then recompute every checksum,
    so only the structural checks (bounds, alignment, loops, overlaps) remain."""
    rng = random.Random(4)
    spans = header_spans(image)
    count = 0
    for _ in range(400):
        off, end = rng.choice(spans)
        buf = bytearray(image)
        field = rng.choice([0, 4, 8, 16])
        if field == 16:
            buf[off + 16 + rng.randrange(end - off - 16)] ^= rng.randrange(1, 256)
        else:
            old = struct.unpack_from(">I", buf, off + field)[0]
            new = rng.choice([old ^ (1 << rng.randrange(32)), rng.randrange(1 << 32),
                              rng.choice([s for s, _e in spans]) | (old & 15),
                              rng.randrange(0, len(image), 16) | (old & 15)])
            struct.pack_into(">I", buf, off + field, new)
        data = refix(buf, spans)
        if data != image:
            assert refused(data), (hex(off), field)
            count += 1
    assert count > 300


def test_bad_checksums_are_refused(image):
    spans = header_spans(image)
    for off, _end in spans:
        for delta in (1, 0x80000000, 0xFFFFFFFF):
            buf = bytearray(image)
            v = struct.unpack_from(">I", buf, off + 12)[0]
            struct.pack_into(">I", buf, off + 12, (v + delta) & 0xFFFFFFFF)
            assert refused(bytes(buf))
    buf = bytearray(image)
    buf[12] ^= 1
    assert refused(bytes(buf))


def test_manifest_lies_are_refused(image, sample_programs):
    """A valid ROMFS whose manifest is damaged or lies in any field."""
    rng = random.Random(5)
    files = read_romfs(image).files()
    raw = files[MANIFEST_NAME]
    doc = json.loads(raw)
    count = 0
    for _ in range(250):          # byte damage inside the manifest, ROMFS rebuilt around it
        buf = bytearray(raw)
        buf[rng.randrange(len(buf))] ^= rng.randrange(1, 256)
        assert refused(write_romfs({**files, MANIFEST_NAME: bytes(buf)}, "plcbuilder"))
        count += 1
    mutations = [
        lambda e: e.update(code_size=e["code_size"] + rng.choice([-1, 1, 1000])),
        lambda e: e.update(file_size=e["file_size"] + rng.choice([-1, 1, 16])),
        lambda e: e.update(crc32=f"{rng.randrange(1 << 32):08x}"),
        lambda e: e.update(kind={"hardware": "software", "software": "hardware"}[e["kind"]]),
        lambda e: e.update(name=e["name"] + "X"),
        lambda e: e.update(file="MANIFEST"),
        lambda e: e.update(code_size=-1),
        lambda e: e.update(code_size=str(e["code_size"])),
        lambda e: e.pop("crc32"),
        lambda e: e.update(extra=1),
    ]
    for _ in range(250):
        entries = [dict(e) for e in doc["procedures"]]
        rng.choice(mutations)(rng.choice(entries))
        limits = Limits(**doc["limits"])
        assert refused(write_romfs({**files, MANIFEST_NAME: manifest_text(entries, limits)},
                                   "plcbuilder"))
        count += 1
    # files that do not match what the manifest says
    names = [n for n in files if n != MANIFEST_NAME]
    for _ in range(100):
        victim = rng.choice(names)
        blob = bytearray(files[victim])
        blob[rng.randrange(len(blob))] ^= rng.randrange(1, 256)
        assert refused(write_romfs({**files, victim: bytes(blob)}, "plcbuilder"))
        swapped = dict(files)
        a, b = rng.sample(names, 2)
        swapped[a], swapped[b] = files[b], files[a]
        assert refused(write_romfs(swapped, "plcbuilder"))
        count += 2
    assert count >= 700


def test_over_limit_images_are_refused(make_program):
    rng = random.Random(6)
    big_limits = Limits(hw_proc=4096, hw_total=65536, sw_proc=65536)
    sw_big = make_program("SW", Kind.SOFTWARE, 16385)
    for case in range(60):
        kind = case % 3
        if kind == 0:      # one hardware procedure over 512 bytes
            progs = [("M80", Kind.HARDWARE, make_program("M80", Kind.HARDWARE, rng.randint(513, 900)))]
            why = r"procedure M80 \(hardware\): code is \d+ bytes, over the 512"
        elif kind == 1:    # each fits, together over 8 KiB
            n = rng.randint(17, 24)
            progs = [(f"M{i}", Kind.HARDWARE, make_program(f"M{i}", Kind.HARDWARE, 500))
                     for i in range(n)]
            why = r"hardware procedures together are \d+ bytes, over the 8192-byte limit"
        else:              # a software procedure over 16 KiB
            progs = [("SW", Kind.SOFTWARE, sw_big)]
            why = r"procedure SW \(software\): code is 16385 bytes"
        progs += [(f"S{i}", Kind.SOFTWARE, make_program(f"S{i}", Kind.SOFTWARE, 50))
                  for i in range(rng.randint(0, 3))]
        img = write_image(progs, big_limits)
        assert read_image(img)                      # fine by the limits it was built for
        with pytest.raises(ImageError, match=why):  # refused by the controller's own
            read_image(img, Limits())
        # and an image whose own manifest names limits it breaks
        files = read_romfs(img).files()
        doc = json.loads(files[MANIFEST_NAME])
        lying = manifest_text(doc["procedures"], Limits())
        assert refused(write_romfs({**files, MANIFEST_NAME: lying}, "plcbuilder"))


def test_non_image_inputs_are_refused():
    rng = random.Random(7)
    for n in (0, 1, 31, 32, 512, 1024, 4096):
        assert refused(bytes(rng.randrange(256) for _ in range(n)))
        assert refused(b"-rom1fs-" + bytes(rng.randrange(256) for _ in range(n)))
    assert refused(write_romfs({}, "plcbuilder"))                       # no manifest
    assert refused(write_romfs({MANIFEST_NAME: b""}, "plcbuilder"))
