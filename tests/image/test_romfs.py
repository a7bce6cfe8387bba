"""The ROMFS writer and reader, checked against the format rules and against
Debian's genromfs (skipped, with the reason, when genromfs is not installed)."""

import os
import random
import struct
import subprocess

import pytest

from plcbuilder.image import romfs
from plcbuilder.image.romfs import ImageError, read_romfs, write_romfs


def u32(buf, off):
    return struct.unpack_from(">I", buf, off)[0]


def sum32(buf, start, end):
    return sum(struct.unpack_from(f">{(end - start) // 4}I", buf, start)) & 0xFFFFFFFF


def headers(image):
    """(offset, end of padded name) of every file header of a valid image."""
    fs = read_romfs(image)
    out = []

    def visit(d):
        for c in d.children:
            raw = c.name.encode()
            out.append((c.offset, c.offset + 16 + (len(raw) + 16) // 16 * 16))
            if c.is_dir and c.name not in (".", ".."):
                visit(c)
    visit(fs.root)
    return out


def refix(buf, hdrs, size=None):
    """Recompute every header checksum and the superblock's after tampering."""
    buf = bytearray(buf)
    for off, end in hdrs:
        struct.pack_into(">I", buf, off + 12, 0)
        struct.pack_into(">I", buf, off + 12, -sum32(buf, off, end) & 0xFFFFFFFF)
    size = u32(buf, 8) if size is None else size
    span = min(512, size)
    struct.pack_into(">I", buf, 12, 0)
    struct.pack_into(">I", buf, 12, -sum32(buf, 0, span) & 0xFFFFFFFF)
    return bytes(buf)


def random_tree(rng, depth=0, allow_dirs=True):
    tree = {}
    for _ in range(rng.randint(0 if depth else 1, 6)):
        n = rng.choice([1, 2, 5, 14, 15, 16, 17, 31, 32, 40])
        name = "".join(rng.choice("abcXYZ019_-.") for _ in range(n))
        if name in (".", "..") or name in tree:
            continue
        if allow_dirs and depth < 3 and rng.random() < 0.2:
            tree[name] = random_tree(rng, depth + 1)
        else:
            size = rng.choice([0, 1, 3, 15, 16, 17, 100, 511, 512, 513, 1000, 3000])
            tree[name] = bytes(rng.randrange(256) for _ in range(size))
    return tree


def materialise(tree, folder):
    os.makedirs(folder, exist_ok=True)
    os.chmod(folder, 0o755)
    for name, value in tree.items():
        path = os.path.join(folder, name)
        if isinstance(value, dict):
            materialise(value, path)
        else:
            with open(path, "wb") as f:
                f.write(value)
            os.chmod(path, 0o644)


def run_genromfs(exe, folder, out, volume):
    subprocess.run([exe, "-f", str(out), "-d", str(folder), "-V", volume],
                   check=True, capture_output=True)
    return out.read_bytes()


# ------------------------------------------------------------- format rules

def test_layout_follows_the_format_rules():
    img = write_romfs({"b.bin": b"hello", "a.bin": b"x" * 40, "sub": {"z": b"zz"}}, "PLC")
    assert img[:8] == b"-rom1fs-"
    size = u32(img, 8)
    assert size % 16 == 0 and len(img) == 1024 and not img[size:].strip(b"\0")
    assert sum32(img, 0, min(512, size)) == 0
    assert img[16:32] == b"PLC".ljust(16, b"\0")
    fs = read_romfs(img)
    names = [c.name for c in fs.root.children]
    assert names == [".", "..", "a.bin", "b.bin", "sub"]      # dots first, then sorted
    dot, dotdot = fs.root.children[:2]
    assert dot.type == romfs.DIRECTORY and dot.executable and dot.spec == dot.offset == 32
    assert dotdot.type == romfs.HARDLINK and dotdot.spec == 32
    sub = fs.root.children[4]
    assert sub.type == romfs.DIRECTORY and sub.executable
    sdot, sdotdot, z = sub.children
    assert (sdot.type, sdot.spec) == (romfs.HARDLINK, sub.offset)
    assert (sdotdot.type, sdotdot.spec) == (romfs.HARDLINK, 32)
    assert z.data == b"zz" and not z.executable
    for off, end in headers(img):
        assert off % 16 == 0 and sum32(img, off, end) == 0
    a = fs.root.children[2]
    assert (a.offset + 32) % 16 == 0 and img[a.offset + 32:a.offset + 72] == b"x" * 40
    assert u32(img, fs.root.children[-1].offset) & ~15 == 0     # last entry ends the chain


def test_output_is_deterministic_whatever_the_insertion_order():
    a = write_romfs({"x": b"1", "b": b"22", "M": {"q": b"", "p": b"3"}})
    b = write_romfs({"M": {"p": b"3", "q": b""}, "b": b"22", "x": b"1"})
    assert a == b


def test_empty_tree_and_long_names():
    img = write_romfs({})
    assert read_romfs(img).files() == {}
    long = "n" * 200
    assert read_romfs(write_romfs({long: b"data"})).files() == {long: b"data"}
    # a name of exactly 16 bytes takes 32 (it needs its NUL)
    fs = read_romfs(write_romfs({"a" * 16: b"z"}))
    node = fs.root.children[2]
    assert fs.size == node.offset + 16 + 32 + 16     # header, name + NUL padding, data


def test_round_trip_of_random_trees():
    rng = random.Random(7)
    for _ in range(60):
        tree = random_tree(rng)
        fs = read_romfs(write_romfs(tree, "vol"))
        assert fs.tree() == tree and fs.volume == "vol"


@pytest.mark.parametrize("tree, why", [
    ({"a/b": b""}, "'/'"),
    ({"": b""}, "empty name"),
    ({"a\0": b""}, "NUL"),
    ({"a": 3}, "bytes or a mapping"),
])
def test_writer_refuses_bad_trees(tree, why):
    with pytest.raises(ImageError, match=why):
        write_romfs(tree)


# ------------------------------------------------------------ reader errors

def sample():
    return write_romfs({"M03.bin": b"A" * 100, "M05.bin": b"B" * 30, "d": {"f": b"C" * 20}}, "v")


def test_reader_names_the_problem():
    img = sample()
    hdrs = headers(img)
    cases = []
    cases.append((b"", "truncated"))
    cases.append((b"-rom2fs-" + img[8:], "not a ROMFS image"))
    cases.append((img[:700], "truncated"))
    cases.append((img + b"\0" * 1024, "trailing data"))
    bad = bytearray(img); bad[40] ^= 1
    cases.append((bytes(bad), "checksum"))
    # a header beyond the first 512 bytes: only its own checksum notices
    late = [h for h in hdrs if h[0] >= 512]
    if late:
        bad = bytearray(img); bad[late[0][0] + 20] ^= 0x40
        cases.append((bytes(bad), r"checksum mismatch \(header and name"))
    # padding bytes after the file system
    bad = bytearray(img); bad[-1] = 7
    cases.append((bytes(bad), "padding after the file system"))
    for data, why in cases:
        with pytest.raises(ImageError, match=why):
            read_romfs(data)


def test_malicious_next_pointers_cannot_loop_or_escape():
    img = sample()
    hdrs = headers(img)
    fs = read_romfs(img)
    m05 = [c for c in fs.root.children if c.name == "M05.bin"][0]
    m03 = [c for c in fs.root.children if c.name == "M03.bin"][0]

    def with_next(node, target, bits=2):
        buf = bytearray(img)
        struct.pack_into(">I", buf, node.offset, target | bits)
        return refix(buf, hdrs)

    with pytest.raises(ImageError, match="loop"):
        read_romfs(with_next(m05, m03.offset))               # back to an earlier header
    with pytest.raises(ImageError, match="loop"):
        read_romfs(with_next(m05, m05.offset))               # to itself
    with pytest.raises(ImageError, match="outside the file system"):
        read_romfs(with_next(m05, 0x7FFFFFF0))
    with pytest.raises(ImageError, match="overlaps"):
        read_romfs(with_next(m03, m03.offset + 48))          # into its own data
    with pytest.raises(ImageError):
        read_romfs(with_next(m03, m03.offset + 8))           # misaligned: low bits are type
    # a directory whose first entry is itself
    d = [c for c in fs.root.children if c.name == "d"][0]
    buf = bytearray(img)
    struct.pack_into(">I", buf, d.offset + 4, d.offset)
    with pytest.raises(ImageError, match="loop"):
        read_romfs(refix(buf, hdrs))


def test_sizes_and_types_are_checked():
    img = sample()
    hdrs = headers(img)
    fs = read_romfs(img)
    m03 = [c for c in fs.root.children if c.name == "M03.bin"][0]
    buf = bytearray(img)
    struct.pack_into(">I", buf, m03.offset + 8, 0x10000000)
    with pytest.raises(ImageError, match="runs past the end"):
        read_romfs(refix(buf, hdrs))
    buf = bytearray(img)
    struct.pack_into(">I", buf, m03.offset + 8, 200)       # data now overlaps the next header
    with pytest.raises(ImageError, match="overlaps"):
        read_romfs(refix(buf, hdrs))
    buf = bytearray(img)
    struct.pack_into(">I", buf, m03.offset + 4, 0x20)       # spec.info of a file must be 0
    with pytest.raises(ImageError, match="must be 0"):
        read_romfs(refix(buf, hdrs))
    dot = fs.root.children[1]                               # ".." pointing elsewhere
    buf = bytearray(img)
    struct.pack_into(">I", buf, dot.offset + 4, m03.offset)
    with pytest.raises(ImageError, match="parent directory"):
        read_romfs(refix(buf, hdrs))
    buf = bytearray(img)                                    # a non-zero gap byte
    gap = m03.offset + 32 + 100
    buf[gap] = 1
    with pytest.raises(ImageError, match="outside every header"):
        read_romfs(refix(buf, hdrs))
    assert read_romfs(refix(buf, hdrs), strict=False).files()["M03.bin"] == b"A" * 100


def test_deep_nesting_is_refused():
    tree: dict = {"f": b"x"}
    for _ in range(romfs.MAX_DEPTH + 2):
        tree = {"d": tree}
    with pytest.raises(ImageError, match="nested"):
        read_romfs(write_romfs(tree))


# --------------------------------------------------------------- genromfs

def test_genromfs_images_read_back_identically(genromfs, tmp_path):
    rng = random.Random(2024)
    for i in range(12):
        tree = random_tree(rng)
        folder = tmp_path / f"t{i}"
        materialise(tree, folder)
        theirs = run_genromfs(genromfs, folder, tmp_path / f"t{i}.img", f"vol{i}")
        fs = read_romfs(theirs)                          # strict: padding, gaps, checksums
        assert fs.volume == f"vol{i}"
        assert fs.tree() == tree
        # Same entry order as genromfs (the host's readdir order) -> same bytes.
        assert write_romfs(fs.ordered_tree(), fs.volume, sort=False) == theirs
        # Our own (sorted) layout holds exactly the same files.
        ours = write_romfs(tree, f"vol{i}")
        assert len(ours) == len(theirs)
        assert read_romfs(ours).tree() == tree


def test_byte_identical_to_genromfs_when_the_order_agrees(genromfs, tmp_path):
    # genromfs puts the root's "." and ".." first and then follows readdir order;
    # with one file in the root that order cannot differ from ours. (In a
    # subdirectory genromfs keeps "." and ".." where readdir lists them.)
    tree = {"M03.bin": bytes(range(256)) * 3}
    materialise(tree, tmp_path / "one")
    assert run_genromfs(genromfs, tmp_path / "one", tmp_path / "one.img", "plcbuilder") \
        == write_romfs(tree, "plcbuilder")
    materialise({}, tmp_path / "empty")
    assert run_genromfs(genromfs, tmp_path / "empty", tmp_path / "e.img", "v") == write_romfs({}, "v")


def test_genromfs_links_read(genromfs, tmp_path):
    d = tmp_path / "links"
    d.mkdir()
    (d / "f").write_bytes(b"abc")
    os.link(d / "f", d / "g")
    os.symlink("f", d / "s")
    fs = read_romfs(run_genromfs(genromfs, d, tmp_path / "l.img", "v"))
    assert fs.files() == {"f": b"abc", "g": b"abc"}
    kinds = {c.name: c.type for c in fs.root.entries()}
    assert romfs.HARDLINK in kinds.values() and kinds["s"] == romfs.SYMLINK
    s = [c for c in fs.root.entries() if c.name == "s"][0]
    assert s.data == b"f"


def test_lazy_files_give_the_same_bytes_and_are_read_in_turn():
    """iter_romfs with LazyFile contents writes exactly what write_romfs writes."""
    from plcbuilder.image.romfs import LazyFile, iter_romfs
    rng = random.Random(7)
    tree = {f"F{i:03d}.bin": rng.randbytes(rng.randrange(0, 900)) for i in range(40)}
    tree["MANIFEST"] = b"{}\n"
    reads = []

    def lazy(name, data):
        def read():
            reads.append(name)
            return data
        return LazyFile(len(data), read)

    lazy_tree = {n: lazy(n, d) for n, d in tree.items()}
    chunks = iter_romfs(lazy_tree)
    assert reads == []                         # planned, nothing read yet
    assert b"".join(chunks) == write_romfs(tree)
    assert sorted(reads) == sorted(tree) and len(reads) == len(tree)
    assert read_romfs(write_romfs(tree)).files() == tree


def test_a_lazy_file_that_changed_size_is_an_error():
    from plcbuilder.image.romfs import LazyFile, iter_romfs
    with pytest.raises(ImageError, match="changed while writing"):
        b"".join(iter_romfs({"A.bin": LazyFile(10, lambda: b"short")}))
