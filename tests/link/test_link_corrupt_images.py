"""More than a thousand damaged, forged or over-limit images, each refused by the
served controller with a reason; after each the previous image is still loaded,
still running, and simulated time still advances."""

import json
import random
import zlib

import pytest

from plcbuilder.bytecode.program import Kind
from plcbuilder.image.manifest import MANIFEST_NAME, Limits, manifest_text, write_image
from plcbuilder.image.romfs import read_romfs, write_romfs
from plcbuilder.link.client import RefusedError
from plcbuilder.link.protocol import MAX_IMAGE
from plcbuilder.link.service import Refused
from tests.link.linkkit import compile_programs, wait_for

VOLUME = "plcbuilder"


def _romfs(files):
    return write_romfs(files, VOLUME)


def corrupted_images(image: bytes) -> list[tuple[str, bytes]]:
    rng = random.Random(20261121)
    out: list[tuple[str, bytes]] = []
    n = len(image)
    files = read_romfs(image).files()
    raw = files[MANIFEST_NAME]
    doc = json.loads(raw)
    limits = Limits(**doc["limits"])
    entries = doc["procedures"]
    bins = [e["file"] for e in entries]

    for _ in range(400):                                   # byte flips
        buf = bytearray(image)
        for _ in range(rng.randint(1, 4)):
            buf[rng.randrange(n)] ^= rng.randrange(1, 256)
        out.append(("flip", bytes(buf)))
    for cut in list(range(0, 40)) + [rng.randrange(n) for _ in range(140)] + [n - 1]:
        out.append(("truncated", image[:cut]))             # truncation
    for extra in (b"\0", b"\0" * 16, b"\0" * 1024, b"x", b"\xff" * 7) * 4:
        out.append(("trailing", image + extra + bytes([rng.randrange(256)])))
    for _ in range(100):                                   # a run of garbage
        start = rng.randrange(n - 64)
        junk = bytes(rng.randrange(256) for _ in range(rng.randint(2, 64)))
        out.append(("garbage run", image[:start] + junk + image[start + len(junk):]))

    def with_manifest(text: bytes, **more) -> bytes:
        return _romfs({**files, **more, MANIFEST_NAME: text})

    def lie(mutate) -> bytes:
        es = [dict(e) for e in entries]
        mutate(rng.choice(es), es)
        return with_manifest(manifest_text(es, limits))

    top = json.loads(raw)
    for version in (0, 2, 3, 99, -1, "1", 1.0, None, True):   # wrong format version
        t = dict(top, version=version)
        out.append(("version", with_manifest(json.dumps(t, sort_keys=True).encode())))
        head = raw.replace(b'"version": 1', b'"version": ' + json.dumps(version).encode())
        out.append(("version in place", with_manifest(head)))
    for fmt in ("plcbuilder-imag", "PLCBUILDER-IMAGE", "", "romfs"):
        out.append(("format", with_manifest(raw.replace(b"plcbuilder-image", fmt.encode()))))
    mutations = [
        ("crc", lambda e, es: e.update(crc32=f"{rng.randrange(1 << 32):08x}")),
        ("crc case", lambda e, es: e.update(crc32=e["crc32"].upper() + "")),
        ("code_size", lambda e, es: e.update(code_size=e["code_size"] + rng.choice([-1, 1, 9]))),
        ("file_size", lambda e, es: e.update(file_size=e["file_size"] + rng.choice([-1, 1, 16]))),
        ("kind", lambda e, es: e.update(kind={"hardware": "software",
                                              "software": "hardware"}[e["kind"]])),
        ("name", lambda e, es: e.update(name=e["name"] + "X")),
        ("file", lambda e, es: e.update(file="OTHER.bin")),
        ("missing key", lambda e, es: e.pop(rng.choice(sorted(e)))),
        ("extra key", lambda e, es: e.update(extra=1)),
        ("duplicate", lambda e, es: es.append(dict(e))),
        ("dropped", lambda e, es: es.remove(e)),
        ("negative", lambda e, es: e.update(code_size=-5)),
        ("text size", lambda e, es: e.update(file_size=str(e["file_size"]))),
    ]
    for _ in range(180):                                   # a manifest that lies
        label, m = rng.choice(mutations)
        data = lie(m)
        if data != image:
            out.append(("manifest " + label, data))
    for _ in range(120):                                   # damaged manifest bytes
        buf = bytearray(raw)
        buf[rng.randrange(len(buf))] ^= rng.randrange(1, 256)
        out.append(("manifest byte", with_manifest(bytes(buf))))
    for _ in range(80):                                    # a .bin damaged, manifest CRCs redone
        victim = rng.choice(bins)
        blob = bytearray(files[victim])
        for _ in range(rng.randint(1, 3)):
            pos = rng.randrange(len(blob))
            blob[pos] ^= rng.randrange(1, 256)
        es = [dict(e) for e in entries]
        for e in es:
            if e["file"] == victim:
                e["crc32"] = f"{zlib.crc32(bytes(blob)):08x}"
        out.append(("consistent lie", with_manifest(manifest_text(es, limits),
                                                    **{victim: bytes(blob)})))
    for _ in range(20):                                    # a file the manifest does not list
        out.append(("stray file", _romfs({**files, f"X{rng.randrange(999)}.bin": b"\0" * 8})))
    for _ in range(20):                                    # two files swapped
        a, b = rng.sample(bins, 2)
        out.append(("swapped", _romfs({**files, a: files[b], b: files[a]})))

    big = Limits(hw_proc=4096, hw_total=1 << 20, sw_proc=1 << 20)
    over_hw = compile_programs(["M80"], {"M80": (Kind.HARDWARE,
                                                 "main(){" + "a=a+123456;" * 60 + "exit(1);}")},
                               code_limit=4096)[0]
    assert over_hw.code_size > 512
    many = [compile_programs([f"M{i}"], {f"M{i}": (Kind.HARDWARE,
                                                   "main(){" + "a=a+123456;" * 45 + "exit(1);}")})[0]
            for i in range(20)]
    assert sum(p.code_size for p in many) > 8192
    for label, progs in (("hw over 512", [over_hw]), ("hw total over 8192", many)):
        built = write_image([(p.name, p.kind, p.to_bytes()) for p in progs], big)
        out += [(label, built)] * 1
        fs = read_romfs(built).files()
        es = json.loads(fs[MANIFEST_NAME])["procedures"]
        out.append((label + " (manifest claims default limits)",
                    _romfs({**fs, MANIFEST_NAME: manifest_text(es, Limits())})))
        for e in es:                                        # and claims small sizes
            e["code_size"] = 10
        out.append((label + " (manifest understates)",
                    _romfs({**fs, MANIFEST_NAME: manifest_text(es, Limits())})))
    for _ in range(30):                                    # not images at all
        k = rng.randrange(4)
        if k == 0:
            out.append(("random", bytes(rng.randrange(256) for _ in range(rng.randint(0, 3000)))))
        elif k == 1:
            out.append(("zeros", b"\0" * rng.randint(0, 4096)))
        elif k == 2:
            out.append(("json", json.dumps({"procedures": []}).encode()))
        else:
            out.append(("romfs magic only", b"-rom1fs-" + bytes(rng.randrange(256)
                                                              for _ in range(rng.randint(0, 600)))))
    out.append(("larger than the upload limit", image + b"\0" * (MAX_IMAGE + 1 - len(image))))
    return [(label, data) for label, data in out if data != image]


@pytest.fixture(scope="module")
def bad_images(image):
    cases = corrupted_images(image)
    assert len(cases) >= 1000
    return cases


def test_corrupted_images_are_all_refused_and_the_old_image_keeps_running(server, bad_images):
    svc = server.service
    sim = server.sim
    loaded = svc.image
    names = set(svc.sim.call(lambda: sim.controller.programs))
    assert loaded is not None and "M88" in names
    svc.dispatch({"type": "start", "name": "M88"}, None)
    t_of = lambda: sim.call(lambda: sim.controller.t_ms)  # noqa: E731
    t = t_of()
    reasons = set()
    for label, data in bad_images:
        with pytest.raises(Refused) as e:
            svc.load_image(data)
        assert e.value.reason.startswith("image refused: "), label
        reasons.add(e.value.reason.split(":")[1].strip()[:12])
        assert svc.image is loaded, label
        assert set(sim.call(lambda: sim.controller.programs)) == names, label
        t = wait_for(lambda: (lambda now: now if now > t else None)(t_of()), timeout=5)
    st = svc.state()
    assert st.running == "M88"              # never interrupted: nothing was loaded
    assert "LUBE" in st.software
    assert svc.refused == len(bad_images) and svc.uploads == 1
    assert len(reasons) > 10                   # the reasons say different things


def test_a_subset_over_a_real_socket(server, client, bad_images, image):
    before = client.state()
    client.start("M88")
    rng = random.Random(7)
    subset = rng.sample(bad_images, 60) + [c for c in bad_images if "larger" in c[0]]
    for label, data in subset:
        with pytest.raises(RefusedError) as e:
            client.upload(data)
        assert e.value.code in ("refused", "bad_request"), label
        assert e.value.reason, label
        st = client.state()
        assert st.image == before.image and st.running == "M88", label
    t = client.state().t_ms
    wait_for(lambda: client.state().t_ms > t)
    # the good image is still accepted afterwards (and restarts the procedures)
    r = client.upload(image)
    assert r["accepted"] and client.state().running is None
