"""The IDE runs a G-code program (SPEC §10, docs/controller.md "G-code jobs"):
Run › Run G-code Program… opens the job on the controller; the run log shows
the lines it reads and the procedures it starts, the run panels' status line
where it is; Pause, Continue and Stop reach it."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from plcbuilder.api import events as ev  # noqa: E402
from plcbuilder.ide.actions import Act  # noqa: E402

WAIT = 30_000


def _log_texts(panels) -> list[str]:
    rows = panels.log.rows
    return [rows.row(i)[3] for i in range(rows.rowCount())]


def test_run_gcode_program_from_the_run_menu(live_uploaded, qtbot, monkeypatch, tmp_path):
    win, panels = live_uploaded
    root = win.project.root
    job = root / "job.nc"
    run_menu = next(a.menu() for a in win.menuBar().actions() if a.text() == "&Run")
    assert win.action(Act.RUN_GCODE) in run_menu.actions()
    from PySide6.QtWidgets import QFileDialog
    monkeypatch.setattr(QFileDialog, "getOpenFileName",
                        staticmethod(lambda *a, **k: (str(job), "")))
    win.run_actions.set_speed("max")
    gcode_verbs = (Act.PAUSE_GCODE, Act.PLAY_GCODE, Act.STOP_GCODE)
    assert not any(win.action(a).isEnabled() for a in gcode_verbs)     # no job open yet
    win.action(Act.RUN_GCODE).trigger()
    qtbot.waitUntil(lambda: any("starts M03" in t for t in _log_texts(panels)), timeout=WAIT)
    qtbot.waitUntil(lambda: any(t.startswith("ended at line 13") for t in _log_texts(panels)),
                    timeout=60_000)
    texts = _log_texts(panels)
    assert "line 3: starts M03" in texts and any(t.startswith("line 3: S12000 M03") for t in texts)
    assert any("starts M84" in t for t in texts)
    # "the procedures it called and their exit codes ... in the run panels" (issue 27.11)
    assert "line 3: M03 exit 99 plc_exit_normal" in texts
    assert "line 12: M05 exit 99 plc_exit_normal" in texts
    qtbot.waitUntil(lambda: "G-code job.nc line 13/13 ended, line 12 M05 → M05 exit 99"
                    in panels.proc.status.plain_text(), timeout=WAIT)
    # an ended job can only be run again
    qtbot.waitUntil(lambda: win.action(Act.PLAY_GCODE).isEnabled(), timeout=WAIT)
    assert not win.action(Act.PAUSE_GCODE).isEnabled()
    assert not win.action(Act.STOP_GCODE).isEnabled()


def test_pause_continue_and_stop_are_offered_as_the_job_allows(live_uploaded, qtbot,
                                                                tmp_path):
    """Pause and Stop while the job runs, Continue and Stop while it is paused,
    only Continue (run it again) once it stopped: the menu follows the job's
    state on the controller."""
    win, _panels = live_uploaded
    dwell = tmp_path / "dwell.nc"
    dwell.write_text("G4 P60\nM30\n")            # a minute's dwell at 1x
    win.run_actions.set_speed("realtime")
    pause, play, stop = (win.action(a) for a in (Act.PAUSE_GCODE, Act.PLAY_GCODE,
                                                  Act.STOP_GCODE))

    def offered():
        return (pause.isEnabled(), play.isEnabled(), stop.isEnabled())

    assert win.run_actions.run_gcode(str(dwell))
    qtbot.waitUntil(lambda: offered() == (True, False, True), timeout=WAIT)
    pause.trigger()
    qtbot.waitUntil(lambda: offered() == (False, True, True), timeout=WAIT)
    stop.trigger()
    qtbot.waitUntil(lambda: offered() == (False, True, False), timeout=WAIT)


def test_a_bad_program_is_refused_naming_its_line(live_uploaded, qtbot, tmp_path):
    win, panels = live_uploaded
    bad = tmp_path / "bad.nc"
    bad.write_text("M03\nG2 X1 Y1\n")
    errors = []
    win.connection.sig_error.connect(errors.append)
    win.connection.sig_refused.connect(lambda verb, why: errors.append(f"{verb}: {why}"))
    assert win.run_actions.run_gcode(str(bad))
    qtbot.waitUntil(lambda: any("bad.nc:2: G2 is not supported" in e for e in errors),
                    timeout=WAIT)


def test_the_log_row_of_a_job_event():
    from plcbuilder.ide.panels.log import event_row
    row = event_row(ev.JobEvent(1200, "/p/job.nc", 7, "running", "M08", "M08"))
    assert row[1] == "job.nc" and row[2] == "job" and row[3] == "line 7: starts M08"
    row = event_row(ev.JobEvent(1250, "/p/job.nc", 7, "running", "M08 exit 99 plc_exit_normal",
                                "M08", 99))
    assert row[3] == "line 7: M08 exit 99 plc_exit_normal"
    row = event_row(ev.JobEvent(1300, "/p/job.nc", 9, "error", "job.nc:9: M71 faulted"))
    assert row[3] == "error at line 9: job.nc:9: M71 faulted" and row[5] == "error"


def test_the_program_an_editor_shows_is_what_runs(live_uploaded, qtbot):
    """Trust (RULES): runs use what the editors show: job.nc edited and not saved
    runs as shown; the file on disk is left alone."""
    win, panels = live_uploaded
    job = win.project.root / "job.nc"
    on_disk = job.read_text()
    ed = win.editor_stack.open_file(str(job))
    ed.setText("S7000 M03\nM30\n")
    results = []
    win.connection.sig_result.connect(lambda verb, r: results.append((verb, r)))
    assert win.run_actions.run_gcode(str(job))
    qtbot.waitUntil(lambda: any(v == "job" for v, _r in results), timeout=WAIT)
    reply = next(r for v, r in results if v == "job")
    assert reply["job"]["lines"] == 2
    qtbot.waitUntil(lambda: "line 1: M03 exit 99 plc_exit_normal" in _log_texts(panels),
                    timeout=WAIT)
    assert job.read_text() == on_disk
    win.editor_stack.close_editor(ed, force=True)       # unsaved: the window would ask


def test_a_procedure_changed_since_the_upload_is_asked_about_first(live_uploaded, qtbot,
                                                                   monkeypatch):
    """As Start does: M05.plc edited and not saved, Run G-code Program asks
    (Build, Upload and Start / Start Anyway / Cancel); Cancel sends nothing,
    Build, Upload and Start builds, uploads, then runs the program."""
    win, panels = live_uploaded
    root = win.project.root
    ed = win.editor_stack.open_file(str(root / "hardware" / "M05.plc"))
    ed.setText(ed.text().replace("exit(99)", "exit(98)"))
    asked, sent = [], []
    monkeypatch.setattr(win.connection, "job", lambda *a: sent.append(a))
    monkeypatch.setattr(win.run_actions, "ask_stale_start",
                        lambda name, reasons: asked.append((name, reasons)))
    assert not win.run_actions.run_gcode(str(root / "job.nc"))
    assert asked[0][0] == "the G-code program job.nc"
    assert "unsaved changes in M05.plc" in asked[0][1] and sent == []
    monkeypatch.setattr(win.run_actions, "ask_stale_start", lambda name, reasons: "build")
    with qtbot.waitSignal(win.sig_build_finished, timeout=60_000):
        assert win.run_actions.run_gcode(str(root / "job.nc"))
    qtbot.waitUntil(lambda: bool(sent), timeout=WAIT)
    assert sent[0][0] == "open" and sent[0][2] == str(root / "job.nc") and sent[0][3] is True
