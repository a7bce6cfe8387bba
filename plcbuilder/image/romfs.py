"""Linux ROMFS (``-rom1fs-``) images: a writer and a strict reader.

The format (all numbers big-endian u32, everything 16-byte aligned)::

    superblock   0  "-rom1fs-"
                 8  full size: bytes of the file system (headers + data)
                12  checksum: the u32 words of the first min(512, full size)
                    bytes sum to 0 (mod 2**32)
                16  volume name, NUL-terminated, zero-padded to 16 bytes
    file header  0  next header offset; the low 4 bits are the type:
                    bit 3 executable, bits 0..2: 0 hard link, 1 directory,
                    2 regular file, 3 symlink, 4 block dev, 5 char dev,
                    6 socket, 7 fifo
                 4  spec.info: a directory's first entry, a hard link's
                    target header, a device's major/minor; 0 otherwise
                 8  size: the data bytes of a regular file or symlink
                12  checksum: header + padded name sum to 0
                16  name, NUL-terminated, zero-padded to 16 bytes
                    then the data (regular files, symlinks)

The writer lays the tree out the way Debian's ``genromfs`` does: depth first,
every directory starting with ``.`` and ``..`` (in the root ``.`` is a directory
entry pointing at itself, ``..`` a hard link to it; in a subdirectory both are
hard links, to the directory's own header and to its parent's), regular files
without the executable bit, directories with it, the full size rounded up to 16
and the file padded with zeros to a multiple of 1024 bytes. Names are sorted
(by their UTF-8 bytes) so the output depends only on the contents; ``genromfs``
takes the order in which the host file system lists the folder, so its image is
byte-identical to ours when that order is the same (``write_romfs(sort=False)``
with the same order reproduces it exactly).

The reader trusts nothing: every checksum, offset, bound and alignment is
checked, no two structures may overlap (so a ``next`` pointer cannot loop), and
in strict mode (the default) every byte that belongs to no structure must be
zero and the image must be exactly as long as ``genromfs`` pads it. Any failure
raises :class:`ImageError` with the reason and the offset.
"""

from __future__ import annotations

import struct
from plcbuilder._support.records import dataclass, field
from typing import Callable, Iterator, Mapping, NoReturn, Optional, Union

MAGIC = b"-rom1fs-"
ALIGN = 16
PAD_TO = 1024
CHECKSUM_SPAN = 512
MAX_IMAGE_SIZE = 64 << 20
MAX_NAME = 1024
MAX_DEPTH = 64
DEFAULT_VOLUME = "plcbuilder"

HARDLINK, DIRECTORY, REGULAR, SYMLINK, BLOCKDEV, CHARDEV, SOCKET, FIFO = range(8)
EXECUTABLE = 8
TYPE_NAMES = ("hard link", "directory", "regular file", "symlink", "block device",
              "char device", "socket", "fifo")

_U32 = struct.Struct(">I")
_HDR = struct.Struct(">IIII")


class ImageError(ValueError):
    """An image that cannot be read or written; the message says exactly why."""


# ----------------------------------------------------------------- helpers

def _align(n: int, a: int = ALIGN) -> int:
    return (n + a - 1) // a * a


def _padded_name_len(raw: bytes) -> int:
    """Bytes a name takes: itself, at least one NUL, up to a multiple of 16."""
    return (len(raw) + ALIGN) // ALIGN * ALIGN


def _sum32(buf: bytes | bytearray | memoryview, start: int, end: int) -> int:
    """The sum of the big-endian u32 words of buf[start:end] (end - start % 4 == 0)."""
    words = struct.unpack_from(f">{(end - start) // 4}I", buf, start)
    return sum(words) & 0xFFFFFFFF


def _fix_checksum(buf: bytearray, start: int, end: int, at: int) -> None:
    _U32.pack_into(buf, at, 0)
    _U32.pack_into(buf, at, (-_sum32(buf, start, end)) & 0xFFFFFFFF)


def _encode_name(name: str, what: str) -> bytes:
    if not isinstance(name, str):
        raise ImageError(f"{what}: name {name!r} is not a string")
    raw = name.encode("utf-8")
    if not raw:
        raise ImageError(f"{what}: empty name")
    if b"\0" in raw or b"/" in raw:
        raise ImageError(f"{what}: name {name!r} contains NUL or '/'")
    if len(raw) > MAX_NAME:
        raise ImageError(f"{what}: name is {len(raw)} bytes, at most {MAX_NAME}")
    return raw


# ------------------------------------------------------------------ writer

#: A tree to write: names mapped to file contents (bytes) or subtrees.
#: With ``sort=False`` a subtree may hold the keys ``"."`` and ``".."`` (value
#: None) to place those entries; they come first otherwise.
Tree = Mapping[str, Union[bytes, bytearray, "LazyFile", "Tree", None]]


@dataclass(frozen=True)
class LazyFile:
    """A file's contents read only when the image is written (a large image is
    never whole in memory): ``size`` bytes that ``read()`` returns."""

    size: int
    read: Callable[[], bytes]


def write_romfs(tree: Tree, volume: str = DEFAULT_VOLUME, *, sort: bool = True) -> bytes:
    """A ROMFS image of ``tree`` (see :data:`Tree`), laid out as genromfs does."""
    return b"".join(iter_romfs(tree, volume, sort=sort))


def iter_romfs(tree: Tree, volume: str = DEFAULT_VOLUME, *, sort: bool = True) -> Iterator[bytes]:
    """The image write_romfs makes, as chunks in order; a file may be a
    :class:`LazyFile`, read when its turn comes. Everything is checked before
    the first chunk."""
    vol = volume.encode("utf-8")
    if b"\0" in vol:
        raise ImageError("volume name contains NUL")
    if len(vol) > MAX_NAME:
        raise ImageError(f"volume name is {len(vol)} bytes, at most {MAX_NAME}")
    first = 16 + _padded_name_len(vol)

    # Pass 1: plan every entry (offsets), depth first, as a flat list.
    plan: list[_Rec] = []

    def order(subtree: Tree, where: str, root: bool) -> list[tuple[str, object]]:
        if not isinstance(subtree, Mapping):
            raise ImageError(f"{where}: a directory must be a mapping")
        items = []
        for name, value in subtree.items():
            if name in (".", ".."):
                if value is not None:
                    raise ImageError(f"{where}: '{name}' must map to None")
                continue
            _encode_name(name, where or "/")
            if not isinstance(value, (bytes, bytearray, LazyFile, Mapping)):
                raise ImageError(f"{where}/{name}: contents must be bytes or a mapping")
            items.append((name, value))
        if sort:
            items.sort(key=lambda kv: kv[0].encode("utf-8"))
            return [(".", None), ("..", None)] + items
        names = list(subtree.keys())
        if root or "." not in names or ".." not in names:
            return [(".", None), ("..", None)] + items
        out, it = [], iter(items)
        for name in names:
            out.append((name, None) if name in (".", "..") else next(it))
        return out

    pos = first

    def place(subtree: Tree, where: str, dir_hdr: int | None, parent: int | None) -> None:
        """Plan one directory's entries starting at ``pos``. dir_hdr is the
        directory's own header (None for the root), parent its parent's."""
        nonlocal pos
        entries = order(subtree, where, dir_hdr is None)
        root_self = pos if dir_hdr is None else None
        indices = []
        for name, value in entries:
            raw = _encode_name(name, where or "/") if name not in (".", "..") else name.encode()
            hdr = pos
            rec = _Rec(raw, hdr)
            indices.append(len(plan))
            plan.append(rec)
            pos = hdr + 16 + _padded_name_len(raw)
            if name == ".":
                if dir_hdr is None:   # the root: a directory entry pointing at itself
                    rec.type, rec.spec = DIRECTORY | EXECUTABLE, root_self
                else:
                    rec.type, rec.spec = HARDLINK, dir_hdr
            elif name == "..":
                rec.type, rec.spec = HARDLINK, root_self if dir_hdr is None else parent
            elif isinstance(value, (bytes, bytearray, LazyFile)):
                data = value if isinstance(value, LazyFile) else bytes(value)
                rec.type, rec.spec, rec.data = REGULAR, 0, data
                pos = _align(pos + _size(data))
            else:
                rec.type, rec.spec = DIRECTORY | EXECUTABLE, pos
                # the parent of a subdirectory of the root is the root's "." entry
                place(value, f"{where}/{name}", hdr, root_self if dir_hdr is None else dir_hdr)
        for a, b in zip(indices, indices[1:]):
            plan[a].next = plan[b].off

    place(tree, "", None, None)
    size = _align(pos)
    if size > MAX_IMAGE_SIZE:
        raise ImageError(f"image would be {size} bytes, more than {MAX_IMAGE_SIZE}")

    return _emit(plan, vol, size)


def _size(data: "bytes | LazyFile") -> int:
    return data.size if isinstance(data, LazyFile) else len(data)


class _Rec:
    """One planned file header: its name, offset, next header and contents."""

    __slots__ = ("name", "off", "next", "type", "spec", "data")

    def __init__(self, name: bytes, off: int):
        self.name, self.off, self.next = name, off, 0
        self.type, self.spec, self.data = 0, 0, b""


def _emit(plan: list[_Rec], vol: bytes, size: int) -> Iterator[bytes]:
    """Pass 2: headers, names, data and checksums, in offset order. The first
    CHECKSUM_SPAN bytes are held back until the superblock's checksum is known."""
    head = bytearray(16 + _padded_name_len(vol))
    head[0:8] = MAGIC
    _U32.pack_into(head, 8, size)
    head[16:16 + len(vol)] = vol
    at = len(head)                  # bytes made so far (head included)
    span = min(CHECKSUM_SPAN, size)
    held: Optional[bytearray] = head

    def put(chunk: bytes) -> Iterator[bytes]:
        nonlocal held
        if held is None:
            if chunk:
                yield chunk
            return
        held += chunk
        if len(held) >= span:
            _fix_checksum(held, 0, span, 12)
            out, held = bytes(held), None
            yield out

    for rec in plan:
        off, data = rec.off, rec.data
        n = _size(data)
        name_end = 16 + _padded_name_len(rec.name)
        hdr = bytearray(name_end)
        _HDR.pack_into(hdr, 0, rec.next | rec.type, rec.spec, n, 0)
        hdr[16:16 + len(rec.name)] = rec.name
        _fix_checksum(hdr, 0, name_end, 12)
        yield from put(bytes(off - at) + hdr)      # alignment padding, then the header
        if isinstance(data, LazyFile):
            data = data.read()
            if len(data) != n:
                raise ImageError(f"{rec.name.decode('utf-8', 'replace')}: {len(data)} bytes "
                                 f"where {n} were planned (changed while writing)")
        yield from put(data)
        at = off + name_end + n
    yield from put(bytes(_align(size, PAD_TO) - at))
    if held is not None:              # a tiny image: all of it within the span
        _fix_checksum(held, 0, span, 12)
        yield bytes(held)


# ------------------------------------------------------------------ reader

@dataclass
class Node:
    """One file header of an image."""

    name: str
    type: int                  # HARDLINK .. FIFO
    executable: bool
    offset: int                # of the header
    spec: int
    size: int
    data: bytes = b""          # regular files and symlinks
    children: list["Node"] = field(default_factory=list)   # directories, in image order
    target: "Node | None" = None                            # hard links

    @property
    def type_name(self) -> str:
        return TYPE_NAMES[self.type]

    @property
    def is_dir(self) -> bool:
        return self.type == DIRECTORY

    @property
    def is_file(self) -> bool:
        return self.type == REGULAR

    def entries(self) -> list["Node"]:
        """Children without ``.`` and ``..``."""
        return [c for c in self.children if c.name not in (".", "..")]


@dataclass
class Romfs:
    volume: str
    size: int                  # the superblock's full size
    root: Node                 # a synthetic directory node holding the root entries

    def walk(self) -> Iterator[tuple[str, Node]]:
        """(path, node) of every entry but ``.``/``..``, depth first, image order."""
        stack: list[tuple[str, Node]] = [("", self.root)]
        while stack:
            prefix, d = stack.pop()
            subdirs = []
            for c in d.entries():
                path = f"{prefix}{c.name}"
                yield path, c
                if c.is_dir:
                    subdirs.append((path + "/", c))
            stack.extend(reversed(subdirs))

    def files(self) -> dict[str, bytes]:
        """Every regular file (hard links to one included) by path."""
        out = {}
        for path, node in self.walk():
            real = node.target if node.type == HARDLINK else node
            if real is not None and real.type == REGULAR:
                out[path] = real.data
        return out

    def tree(self) -> dict:
        """Regular files and directories as nested dicts (write_romfs's input)."""
        def conv(d: Node) -> dict:
            out: dict = {}
            for c in d.entries():
                real = c.target if c.type == HARDLINK else c
                if real is None:
                    continue
                if real.type == REGULAR:
                    out[c.name] = real.data
                elif c.type == DIRECTORY:
                    out[c.name] = conv(c)
            return out
        return conv(self.root)

    def ordered_tree(self) -> dict:
        """Like tree(), but keeping image order and the places of ``.``/``..``:
        ``write_romfs(r.ordered_tree(), r.volume, sort=False)`` rebuilds the image."""
        def conv(d: Node) -> dict:
            out: dict = {}
            for c in d.children:
                if c.name in (".", ".."):
                    out[c.name] = None
                elif c.type == REGULAR:
                    out[c.name] = c.data
                elif c.type == DIRECTORY:
                    out[c.name] = conv(c)
                else:
                    raise ImageError(f"{c.name}: a {c.type_name} cannot be rewritten")
            return out
        return conv(self.root)


class _Reader:
    def __init__(self, data: bytes, strict: bool):
        self.data = data
        self.strict = strict
        self.owner = bytearray(0)      # 1 where a structure lies
        self.headers: dict[int, Node] = {}
        self.next_of: dict[int, int] = {}
        self.size = 0

    def fail(self, msg: str) -> NoReturn:
        raise ImageError(msg)

    def claim(self, start: int, end: int, what: str) -> None:
        if end > self.size:
            self.fail(f"{what} runs past the end of the file system "
                      f"(0x{end:x} > full size 0x{self.size:x})")
        if self.owner.find(1, start, end) >= 0:
            self.fail(f"{what} overlaps another structure at 0x{start:x}..0x{end:x}")
        self.owner[start:end] = b"\1" * (end - start)

    def read(self) -> Romfs:
        data = self.data
        if len(data) < 32:
            self.fail(f"truncated: {len(data)} bytes, a ROMFS superblock needs 32")
        if data[:8] != MAGIC:
            self.fail(f"not a ROMFS image (magic {bytes(data[:8])!r}, expected {MAGIC!r})")
        size = _U32.unpack_from(data, 8)[0]
        self.size = size
        if size < 32:
            self.fail(f"superblock: full size {size} is smaller than the superblock")
        if size % ALIGN:
            self.fail(f"superblock: full size {size} is not a multiple of {ALIGN}")
        if size > len(data):
            self.fail(f"truncated: the superblock says {size} bytes, the image has {len(data)}")
        if self.strict and len(data) != _align(size, PAD_TO):
            self.fail(f"image is {len(data)} bytes; a full size of {size} pads to "
                      f"{_align(size, PAD_TO)} (truncated or trailing data)")
        span = min(CHECKSUM_SPAN, size)
        if _sum32(data, 0, span):
            self.fail(f"superblock checksum mismatch: the first {span} bytes sum to "
                      f"0x{_sum32(data, 0, span):08x}, not 0")
        self.owner = bytearray(size)
        vol_raw, vol_end = self.name_at(16, "volume name")
        self.claim(0, vol_end, "superblock")
        try:
            volume = vol_raw.decode("utf-8")
        except UnicodeDecodeError:
            self.fail("superblock: volume name is not UTF-8")
        root = Node("", DIRECTORY, True, -1, vol_end, 0)
        root.children = self.read_dir(vol_end, root, None, 0, "/")
        self.resolve_links()
        self.check_dots(root, None, "/")
        if self.strict:
            i = self.owner.find(0)
            while 0 <= i < size:
                j = self.owner.find(1, i)
                j = size if j < 0 else j
                gap = data[i:j]
                if gap.strip(b"\0"):
                    k = i + len(gap) - len(gap.lstrip(b"\0"))
                    self.fail(f"unexpected non-zero byte 0x{data[k]:02x} at 0x{k:x}, "
                              "outside every header and file")
                i = self.owner.find(0, j)
            tail = bytes(data[size:])
            if tail.strip(b"\0"):
                i = size + len(tail) - len(tail.lstrip(b"\0"))
                self.fail(f"unexpected non-zero byte at 0x{i:x} in the padding after "
                          f"the file system (full size 0x{size:x})")
        return Romfs(volume, size, root)

    def name_at(self, start: int, what: str) -> tuple[bytes, int]:
        """A NUL-terminated name at start and the end of its 16-byte padding."""
        limit = min(self.size, start + MAX_NAME + 1)
        nul = self.data.find(b"\0", start, limit)
        if nul < 0:
            if limit >= self.size:
                self.fail(f"{what} at 0x{start:x} runs past the end of the file system")
            self.fail(f"{what} at 0x{start:x} is longer than {MAX_NAME} bytes")
        raw = bytes(self.data[start:nul])
        end = start + _padded_name_len(raw)
        if end > self.size:
            self.fail(f"{what} at 0x{start:x}: its padding runs past the end of the file system")
        if self.data[nul:end].strip(b"\0"):
            self.fail(f"{what} at 0x{start:x}: non-zero bytes in the padding after the name")
        return raw, end

    def read_dir(self, first: int, d: Node, parent: Node | None, depth: int, path: str) -> list[Node]:
        if depth > MAX_DEPTH:
            self.fail(f"{path}: directories nested more than {MAX_DEPTH} deep")
        children: list[Node] = []
        names: set[str] = set()
        off = first
        while True:
            node = self.read_header(off, path)
            if node.name in names:
                self.fail(f"{path}: two entries named {node.name!r} (second at 0x{off:x})")
            names.add(node.name)
            children.append(node)
            if node.type == DIRECTORY and node.name not in (".", ".."):
                node.children = self.read_dir(node.spec, node, d, depth + 1, f"{path}{node.name}/")
            nxt = self.next_of[off]
            if nxt == 0:
                return children
            off = nxt

    def read_header(self, off: int, path: str) -> Node:
        where = f"file header at 0x{off:x} in {path}"
        if off % ALIGN:
            self.fail(f"{where}: offset is not a multiple of {ALIGN}")
        if off + 16 > self.size:
            self.fail(f"{where} lies past the end of the file system (full size 0x{self.size:x})")
        if off in self.headers:
            self.fail(f"{where}: a loop (this header was reached before)")
        nxt_raw, spec, size, _ck = _HDR.unpack_from(self.data, off)
        raw, name_end = self.name_at(off + 16, f"name of the {where}")
        try:
            name = raw.decode("utf-8")
        except UnicodeDecodeError:
            self.fail(f"{where}: name {raw!r} is not UTF-8")
        where = f"file header at 0x{off:x} ({path}{name})"
        if not raw:
            self.fail(f"{where}: empty name")
        if b"/" in raw:
            self.fail(f"{where}: name contains '/'")
        self.claim(off, name_end, where)
        total = _sum32(self.data, off, name_end)
        if total:
            self.fail(f"{where}: checksum mismatch (header and name sum to 0x{total:08x}, not 0)")
        ftype = nxt_raw & 7
        node = Node(name, ftype, bool(nxt_raw & EXECUTABLE), off, spec, size)
        self.headers[off] = node
        nxt = nxt_raw & ~15
        if nxt and (nxt < 32 or nxt >= self.size):
            self.fail(f"{where}: next header 0x{nxt:x} is outside the file system")
        if ftype in (REGULAR, SYMLINK):
            if spec != 0:
                self.fail(f"{where}: spec.info of a {TYPE_NAMES[ftype]} must be 0, is 0x{spec:x}")
            if size > self.size - name_end:
                self.fail(f"{where}: data of {size} bytes runs past the end of the file system "
                          f"(full size 0x{self.size:x})")
            self.claim(name_end, name_end + size, f"data of {where}")
            node.data = bytes(self.data[name_end:name_end + size])
        else:
            if size != 0:
                self.fail(f"{where}: size of a {TYPE_NAMES[ftype]} must be 0, is {size}")
            if ftype in (SOCKET, FIFO) and spec != 0:
                self.fail(f"{where}: spec.info of a {TYPE_NAMES[ftype]} must be 0, is 0x{spec:x}")
            if ftype in (HARDLINK, DIRECTORY):
                if spec % ALIGN or spec < 32 or spec + 16 > self.size:
                    self.fail(f"{where}: {'link target' if ftype == HARDLINK else 'first entry'} "
                              f"0x{spec:x} is not a header offset inside the file system")
        self.next_of[off] = nxt
        return node

    def resolve_links(self) -> None:
        for node in self.headers.values():
            if node.type != HARDLINK:
                continue
            target = self.headers.get(node.spec)
            if target is None:
                self.fail(f"hard link {node.name!r} at 0x{node.offset:x}: target 0x{node.spec:x} "
                          "is not a file header")
            if target.type == HARDLINK:
                self.fail(f"hard link {node.name!r} at 0x{node.offset:x}: target 0x{node.spec:x} "
                          "is itself a hard link")
            node.target = target

    def check_dots(self, d: Node, parent: Node | None, path: str) -> None:
        """'.' and '..' must point where genromfs points them."""
        is_root = parent is None
        for c in d.children:
            if c.name == "." or c.name == "..":
                if is_root:
                    ok_self = {d.spec} | {x.offset for x in d.children if x.name == "."}
                    if c.name == "." and c.type == DIRECTORY:
                        ok = c.spec == d.spec
                    else:
                        ok = c.type == HARDLINK and c.spec in ok_self
                else:
                    want = d.offset if c.name == "." else parent.offset
                    if c.name == ".." and parent.offset < 0:   # parent is the root
                        ok = c.type == HARDLINK and (c.spec == parent.spec or
                              c.spec in {x.offset for x in parent.children if x.name == "."})
                    else:
                        ok = c.type == HARDLINK and c.spec == want
                if not ok:
                    self.fail(f"{path}{c.name} at 0x{c.offset:x}: does not point at "
                              f"{'its own directory' if c.name == '.' else 'the parent directory'}")
            elif c.type == DIRECTORY:
                self.check_dots(c, d, f"{path}{c.name}/")


def read_romfs(data: bytes | bytearray | memoryview, *, strict: bool = True) -> Romfs:
    """Parse and validate a ROMFS image; raises ImageError with the reason.

    strict: also require every unused byte to be zero and the image to be
    exactly as long as genromfs pads it (the full size rounded up to 1024).
    """
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise ImageError("an image must be bytes")
    data = bytes(data)
    if len(data) > MAX_IMAGE_SIZE:
        raise ImageError(f"image is {len(data)} bytes, more than {MAX_IMAGE_SIZE}")
    return _Reader(data, strict).read()
