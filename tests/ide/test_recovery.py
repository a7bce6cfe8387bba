"""Recovery copies, atomic saves, the disk watcher, and the settings store."""

import json
import os

from plcbuilder.ide.recovery import (DiskWatcher, RecoveryManager, digest, file_digest,
                                     save_text)
from plcbuilder.ide.settings import MAX_RECENT, Preferences, Settings


def test_recovery_copies_come_and_go(qtbot, tmp_path):
    state = {"items": [(str(tmp_path / "a.plc"), "text é", str(tmp_path))]}
    rm = RecoveryManager(tmp_path / "rec", lambda: state["items"], interval_s=1)
    assert rm.autosave_now() == 1
    index = json.loads((tmp_path / "rec" / "index.json").read_text())
    (entry,) = index.values()
    assert (tmp_path / "rec" / entry["copy"]).read_text(encoding="utf-8") == "text é"
    assert entry["pid"] == os.getpid()
    # our own copies are not offered to ourselves
    assert rm.pending(tmp_path) == []
    # the file was saved: its copy goes at the next autosave
    state["items"] = []
    rm.autosave_now()
    assert json.loads((tmp_path / "rec" / "index.json").read_text()) == {}
    assert [p.name for p in (tmp_path / "rec").iterdir()] == ["index.json"]


def test_copies_of_a_dead_session_are_pending(qtbot, tmp_path):
    rm = RecoveryManager(tmp_path / "rec", lambda: [(str(tmp_path / "p" / "a.plc"), "x", str(tmp_path / "p"))])
    rm.autosave_now()
    index_path = tmp_path / "rec" / "index.json"
    index = json.loads(index_path.read_text())
    for v in index.values():
        v["pid"] = 999999999
    index_path.write_text(json.dumps(index))
    fresh = RecoveryManager(tmp_path / "rec", lambda: [])
    (p,) = fresh.pending(tmp_path / "p")
    assert p["text"] == "x" and p["path"] == str(tmp_path / "p" / "a.plc")
    assert fresh.pending(tmp_path / "elsewhere") == []
    fresh.forget(p["path"])
    assert fresh.pending() == []


def test_a_broken_index_is_ignored(qtbot, tmp_path):
    (tmp_path / "rec").mkdir()
    (tmp_path / "rec" / "index.json").write_text("{not json")
    rm = RecoveryManager(tmp_path / "rec", lambda: [])
    assert rm.pending() == []
    rm.discard_all_own()


def test_save_text_is_atomic_and_keeps_line_ends(tmp_path):
    p = tmp_path / "f.plc"
    d = save_text(p, "a\nb é\n", "\r\n")
    assert p.read_bytes() == "a\r\nb é\r\n".encode()
    assert d == digest(p.read_bytes()) == file_digest(p)
    assert file_digest(tmp_path / "missing") is None


def test_disk_watcher_ignores_own_writes_and_sees_others(qtbot, tmp_path):
    p = tmp_path / "f.plc"
    p.write_text("one")
    w = DiskWatcher()
    changed, deleted = [], []
    w.sig_changed.connect(changed.append)
    w.sig_deleted.connect(deleted.append)
    w.watch(p, file_digest(p))
    # our own save: tell the watcher first
    w.set_digest(p, digest(b"two"))
    save_text(p, "two")
    qtbot.wait(300)
    assert changed == []
    # someone else's atomic save: noticed, and the watch is re-armed
    tmp = tmp_path / "x.tmp"
    tmp.write_text("three")
    os.replace(tmp, p)
    qtbot.waitUntil(lambda: changed == [str(p)], timeout=5000)
    p.write_text("four")
    qtbot.waitUntil(lambda: len(changed) == 2, timeout=5000)
    p.unlink()
    qtbot.waitUntil(lambda: deleted == [str(p)], timeout=5000)
    assert w.check(p) is None                 # reported once
    w.unwatch(p)


def test_check_all_catches_what_the_watcher_missed(qtbot, tmp_path):
    p = tmp_path / "f.plc"
    p.write_text("a")
    w = DiskWatcher()
    w.watch(p, digest(b"something else"))
    changed = []
    w.sig_changed.connect(changed.append)
    w.check_all()
    assert changed == [str(p)]


# ------------------------------------------------------------------ settings
def test_settings_round_trip(qtbot, tmp_path):
    s = Settings(str(tmp_path / "s.ini"))
    assert s.preferences() == Preferences()
    prefs = Preferences(font_size=13, theme="dark", autocomplete=False, autosave_seconds=30)
    s.save_preferences(prefs)
    for i in range(MAX_RECENT + 3):
        d = tmp_path / f"p{i}"
        d.mkdir()
        s.add_recent_project(d)
    s.save_session(tmp_path / "p1", ["/a.plc", "/b.plc"], "/b.plc")
    s.sync()
    s2 = Settings(str(tmp_path / "s.ini"))
    assert s2.preferences() == prefs
    recent = s2.recent_projects()
    assert len(recent) == MAX_RECENT and recent[0].endswith(f"p{MAX_RECENT + 2}")
    assert s2.open_files(tmp_path / "p1") == ["/a.plc", "/b.plc"]
    assert s2.current_file(tmp_path / "p1") == "/b.plc"
    assert s2.open_files(tmp_path / "p2") == []
    s2.remove_recent_project(recent[0])
    assert recent[0] not in s2.recent_projects()
    assert s2.recovery_dir() == tmp_path / "recovery"
    assert Preferences(font_size=9).editor_prefs().font_size == 9


def test_settings_survive_garbage(qtbot, tmp_path):
    f = tmp_path / "s.ini"
    f.write_text("[preferences]\nfont_size=big\ntheme=dark\nhover=nope\n")
    p = Settings(str(f)).preferences()
    assert p.font_size == Preferences().font_size and p.theme == "dark" and p.hover is False
