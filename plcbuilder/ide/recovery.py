"""Not losing work: crash recovery, atomic saves, and files changed on disk.

:class:`RecoveryManager` copies the text of every editor with unsaved
changes to a recovery folder every few seconds (atomically, with an
``index.json`` naming the original files). A clean save or close removes a
file's copy; whatever is left when the IDE starts again was left by a crash,
and is offered back.

:class:`DiskWatcher` notices when an open file changes on disk. It compares
contents (a SHA-256), so the IDE's own saves — whose digest it is told
before writing — never count as changes. ``QFileSystemWatcher`` stops
watching a file that an atomic save replaced, so every notification
re-arms the watch, and a file that is briefly missing (mid-replace) is
looked at again before it is called deleted.

:func:`save_text` is the one way the IDE writes a source file: atomic
(:func:`plcbuilder._support.files.atomic_write`), in UTF-8, with the file's
own line ends.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Callable, Optional

from PySide6.QtCore import QFileSystemWatcher, QObject, QTimer, Signal

from plcbuilder.ide.editor import file_key
from plcbuilder._support.files import atomic_write, read_bounded

#: The largest file the editor opens (and the recovery copies it keeps).
MAX_EDIT_BYTES = 16 << 20
from plcbuilder._support.procs import pid_alive

INDEX = "index.json"


def digest(data: bytes) -> str:
    import hashlib              # (not before the window's first paint)
    return hashlib.sha256(data).hexdigest()


def copy_name(key: str) -> str:
    """The name of a file's recovery copy in the folder (from its file key)."""
    import hashlib
    return hashlib.sha1(key.encode("utf-8", "surrogatepass")).hexdigest()[:16] + ".txt"


def encode_text(text: str, eol: str = "\n") -> bytes:
    if eol != "\n":
        text = text.replace("\n", eol)
    return text.encode("utf-8", "surrogatepass")


def save_text(path, text: str, eol: str = "\n") -> str:
    """Write text atomically; returns the digest of what was written."""
    data = encode_text(text, eol)
    atomic_write(path, data)
    return digest(data)


def file_digest(path) -> Optional[str]:
    try:
        return digest(read_bounded(path, MAX_EDIT_BYTES, "file to edit"))
    except OSError:
        return None


# ------------------------------------------------------------------ recovery
class RecoveryManager(QObject):
    """Autosaves unsaved editors to a recovery folder; offers them back."""

    sig_autosaved = Signal(int)
    """An autosave ran: how many files have a recovery copy."""

    def __init__(self, folder, snapshot: Callable[[], list], parent=None, interval_s: int = 5):
        """``snapshot()`` returns [(path, text, project_root)] of every editor
        with unsaved changes."""
        super().__init__(parent)
        self.folder = Path(folder)
        self.snapshot = snapshot
        self._written: dict[str, str] = {}        # file key -> digest of the copy
        self._on = False                          # started (and not stopped)
        self.timer = QTimer(self)
        self.timer.timeout.connect(self.autosave_now)
        self.set_interval(interval_s)

    def set_interval(self, seconds: int) -> None:
        self.timer.setInterval(max(1, int(seconds)) * 1000)

    def start(self) -> None:
        """Autosave from now on. The timer runs only while an editor has
        unsaved changes (:meth:`poke` says one may have; an autosave that
        finds none stops it): an IDE with nothing unsaved is not woken."""
        self._on = True
        try:
            unsaved = bool(self.snapshot())
        except Exception:  # noqa: BLE001 - never let autosave break the IDE
            unsaved = True
        if unsaved:
            self.timer.start()

    def stop(self) -> None:
        self._on = False
        self.timer.stop()

    def poke(self) -> None:
        """An editor has unsaved changes now: autosave within the interval."""
        if self._on and not self.timer.isActive():
            self.timer.start()

    # ------------------------------------------------------------- writing
    def autosave_now(self) -> int:
        """Write a copy of every unsaved editor; drop copies no longer needed."""
        try:
            items = self.snapshot()
        except Exception:  # noqa: BLE001 - never let autosave break the IDE
            return 0
        index = self._read_index()
        live = set()
        changed = False
        for path, text, project in items:
            key = file_key(path)
            live.add(key)
            data = text.encode("utf-8", "surrogatepass")
            d = digest(data)
            if self._written.get(key) == d and key in index:
                continue
            name = copy_name(key)
            try:
                self.folder.mkdir(parents=True, exist_ok=True)
                atomic_write(self.folder / name, data)
            except OSError:
                continue
            index[key] = {"path": str(path), "copy": name, "time": time.time(),
                          "project": str(project) if project else "", "pid": os.getpid()}
            self._written[key] = d
            changed = True
        for key in [k for k, v in index.items() if k not in live and v.get("pid") == os.getpid()]:
            self._remove(index, key)
            changed = True
        if changed:
            self._write_index(index)
        if not live:
            self.timer.stop()                     # nothing unsaved: until poke()
        self.sig_autosaved.emit(len(live))
        return len(live)

    def discard(self, path) -> None:
        """The file was saved or closed without saving: its copy goes."""
        key = file_key(path)
        self._written.pop(key, None)
        index = self._read_index()
        if key in index:
            self._remove(index, key)
            self._write_index(index)

    def discard_all_own(self) -> None:
        """A clean exit: remove every copy this process wrote."""
        index = self._read_index()
        mine = [k for k, v in index.items() if v.get("pid") == os.getpid()]
        for k in mine:
            self._remove(index, k)
        if mine:
            self._write_index(index)
        self._written.clear()

    # ------------------------------------------------------------- reading
    def pending(self, project_root=None) -> list[dict]:
        """Copies left by another (crashed) session: [{path, text, time, project}],
        only those of project_root when it is given."""
        index = self._read_index()
        out = []
        root = file_key(project_root) if project_root else None
        for key, entry in sorted(index.items()):
            pid = entry.get("pid")
            if pid == os.getpid() or (isinstance(pid, int) and pid_alive(pid)):
                continue            # this session's own, or another IDE's that still runs
            if root is not None:
                project = entry.get("project") or ""
                inside = file_key(project) == root if project else key.startswith(root + os.sep)
                if not inside:
                    continue
            try:
                text = read_bounded(self.folder / entry["copy"], MAX_EDIT_BYTES).decode(
                    "utf-8", "surrogatepass")
            except (OSError, KeyError, UnicodeDecodeError):
                continue
            out.append({"path": entry.get("path", key), "text": text,
                        "time": entry.get("time", 0), "project": entry.get("project", "")})
        return out

    def forget(self, path) -> None:
        """Drop a pending copy (restored or declined)."""
        key = file_key(path)
        index = self._read_index()
        if key in index:
            self._remove(index, key)
            self._write_index(index)

    # ------------------------------------------------------------- private
    def _read_index(self) -> dict:
        try:
            data = json.loads(read_bounded(self.folder / INDEX, MAX_EDIT_BYTES).decode("utf-8"))
            return data if isinstance(data, dict) else {}
        except (OSError, ValueError, RecursionError):
            return {}

    def _write_index(self, index: dict) -> None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            atomic_write(self.folder / INDEX, json.dumps(index, indent=1, sort_keys=True))
        except OSError:
            pass

    def _remove(self, index: dict, key: str) -> None:
        entry = index.pop(key, None)
        if entry and entry.get("copy"):
            try:
                (self.folder / entry["copy"]).unlink()
            except OSError:
                pass


# ------------------------------------------------------------------ disk
class DiskWatcher(QObject):
    """Reports open files whose contents changed on disk (not by the IDE)."""

    sig_changed = Signal(str)
    """The file's contents on disk changed (path)."""

    sig_deleted = Signal(str)
    """The file is gone from disk (path)."""

    RECHECK_MS = 150

    def __init__(self, parent=None):
        super().__init__(parent)
        self.watcher = QFileSystemWatcher(self)
        self.watcher.fileChanged.connect(self._on_file_changed)
        self._digests: dict[str, tuple[str, Optional[str]]] = {}   # key -> (path, digest)
        self._missing: dict[str, int] = {}
        self._suspended = 0

    def watch(self, path, known_digest: Optional[str]) -> None:
        key = file_key(path)
        self._digests[key] = (str(path), known_digest)
        if Path(path).exists() and str(path) not in self.watcher.files():
            self.watcher.addPath(str(path))

    def unwatch(self, path) -> None:
        key = file_key(path)
        entry = self._digests.pop(key, None)
        if entry and entry[0] in self.watcher.files():
            self.watcher.removePath(entry[0])

    def set_digest(self, path, known_digest: Optional[str]) -> None:
        """What the file holds now (the IDE is about to write, or just read, it)."""
        self.watch(path, known_digest)

    def known_digest(self, path) -> Optional[str]:
        entry = self._digests.get(file_key(path))
        return entry[1] if entry else None

    def check(self, path) -> Optional[str]:
        """Look at one file now: 'changed', 'deleted' or None (and signal it)."""
        key = file_key(path)
        entry = self._digests.get(key)
        if entry is None:
            return None
        p, known = entry
        if not Path(p).exists():
            if known is None:
                return None
            self._digests[key] = (p, None)
            self.sig_deleted.emit(p)
            return "deleted"
        if p not in self.watcher.files():
            self.watcher.addPath(p)                  # re-arm after an atomic replace
        now = file_digest(p)
        if now is not None and now != known:
            self._digests[key] = (p, now)
            self.sig_changed.emit(p)
            return "changed"
        return None

    def check_all(self) -> None:
        for p, _d in list(self._digests.values()):
            self.check(p)

    def _on_file_changed(self, path: str) -> None:
        if Path(path).exists():
            self.check(path)
        else:
            # an atomic replace removes and renames: look again shortly
            QTimer.singleShot(self.RECHECK_MS, lambda p=path: self.check(p))
