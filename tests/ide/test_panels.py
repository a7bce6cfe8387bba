"""The run panels without a controller: ring buffers, the run model, and the
docks driven through a stand-in connection."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore, QtWidgets  # noqa: E402

from plcbuilder.controller import events as ev  # noqa: E402
from plcbuilder.ide.panels import (default_pin_names,  # noqa: E402
                                   pin_names_from_defines, pin_names_from_header)
from plcbuilder.ide.panels.log import CATEGORY, TEXT, event_row  # noqa: E402
from plcbuilder.ide.panels.model import RunModel  # noqa: E402
from plcbuilder.ide.ringbuffer import RingBuffer  # noqa: E402
from plcbuilder.link.client import ControllerStatus  # noqa: E402
from tests.ide._workbench import docked_run_panels  # noqa: E402

Qt = QtCore.Qt


# ------------------------------------------------------------------ helpers
class FakeConnection(QtCore.QObject):
    """The ControllerConnection interface, recording the requests."""
    sig_connected = QtCore.Signal(str)
    sig_disconnected = QtCore.Signal(str)
    sig_state = QtCore.Signal(object, int)
    sig_events = QtCore.Signal(list)
    sig_samples = QtCore.Signal(list)
    sig_error = QtCore.Signal(str)
    sig_variables = QtCore.Signal(object)
    sig_note = QtCore.Signal(str)

    def __init__(self):
        super().__init__()
        self.connected = False
        self.calls: list[tuple] = []

    def set_input(self, pin, v):
        self.calls.append(("input", pin, v))

    def set_adc(self, ch, v):
        self.calls.append(("adc", ch, v))

    def request_variables(self):
        self.calls.append(("variables",))


def sample(t, *, proc=0, outputs=0, inputs=0, pwm=(), dac=(), adc=(), axes=(), vel=(),
           running="M03", message=0):
    pad = lambda v, n: tuple(v) + (0,) * (n - len(v))  # noqa: E731
    return ev.Sample(t_ms=t, running=running, proc=proc, message=message,
                     inputs=pad((inputs,), 8), outputs=pad((outputs,), 8), pwm=pad(pwm, 8),
                     dac=pad(dac, 8), adc=pad(adc, 8), axes=pad(axes, 9), velocities=pad(vel, 9))


@pytest.fixture
def fake():
    return FakeConnection()


@pytest.fixture
def panels(qtbot, fake):
    _win, p = docked_run_panels(qtbot, fake, (1400, 900), capacity=2000)
    yield p
    p.shutdown()


# ------------------------------------------------------------------ ring buffer
def test_ring_buffer_keeps_the_newest_in_order():
    rb = RingBuffer(5, 2)
    assert len(rb) == 0 and rb.view().size == 0 and rb.latest() is None
    for i in range(3):
        rb.append((i, 10 * i))
    assert rb.view(0).tolist() == [0, 1, 2]
    rb.extend(np.array([[3, 30], [4, 40], [5, 50], [6, 60]]))
    assert len(rb) == 5 and rb.total == 7
    assert rb.view(0).tolist() == [2, 3, 4, 5, 6]
    assert rb.view(1, last=2).tolist() == [50, 60]
    assert rb.views().shape == (2, 5)
    assert rb.latest().tolist() == [6, 60]
    rb.extend(np.arange(24).reshape(12, 2))           # more than the capacity at once
    assert rb.view(0).tolist() == [14, 16, 18, 20, 22] and rb.total == 19
    with pytest.raises(ValueError):
        rb.view(0)[0] = 1                              # read-only views
    rb.clear()
    assert len(rb) == 0


def test_ring_buffer_matches_a_list_under_random_writes():
    rng = np.random.default_rng(1)
    rb = RingBuffer(37, 1)
    ref: list[float] = []
    for _ in range(200):
        n = int(rng.integers(0, 50))
        vals = rng.random(n)
        rb.extend(vals)
        ref.extend(vals.tolist())
        assert rb.view().tolist() == ref[-37:]


# ------------------------------------------------------------------ model
def test_model_ingests_samples():
    m = RunModel(capacity=100)
    m.add_samples([sample(t, proc=70 if t >= 5 else 0, outputs=0b101 if t >= 3 else 0,
                          inputs=1 << 9 if t >= 4 else 0, pwm=(0, 250), axes=(10000, 0, 2000),
                          vel=(0, 0, 0)) for t in range(10)])
    assert len(m) == 10 and m.t_end == pytest.approx(0.009)
    assert m.active_outputs == {0, 2}
    assert m.active_inputs == {9}
    assert m.proc_values == {0, 70}
    assert m.active_analog() == [1]                    # PWM1 only
    assert m.active_axes() == [0, 2]                   # X and Z sit off zero
    assert m.axes.view(0)[-1] == pytest.approx(100.0)  # mm
    assert m.bit_series("outputs", 2).tolist() == [0, 0, 0] + [1] * 7
    assert m.pin_state("inputs", 9) == 1 and m.pin_state("outputs", 1) == 0
    a, b = m.window(0.0035, 0.006)
    assert m.time.view()[a:b].tolist() == pytest.approx([0.003, 0.004, 0.005, 0.006, 0.007])
    # an older time means the controller started over
    epoch = m.epoch
    m.add_samples([sample(0), sample(1)])
    assert m.epoch == epoch + 1 and len(m) == 2 and m.active_outputs == set()


def test_held_samples_are_kept_as_any_other(monkeypatch):
    """Issue 26.4: a batch that only holds the newest value (the telemetry's
    steps while nothing changes) takes a short way in; the buffers and what
    the model found are exactly those of the long way, also across the ring's
    wrap and after a message or a change."""
    from plcbuilder.ide.panels import model as model_mod
    rng = np.random.default_rng(7)
    fast, slow = RunModel(capacity=53), RunModel(capacity=53)
    monkeypatch.setattr(slow, "_holds", lambda samples: False)
    held = 0
    t = 0
    last = sample(0)
    for _ in range(120):
        batch = []
        for _ in range(int(rng.integers(1, 9))):
            t += int(rng.integers(1, 30))
            if rng.random() < 0.25:          # a change (sometimes with a message)
                last = sample(t, proc=int(rng.integers(0, 3)), outputs=int(rng.integers(0, 4)),
                              inputs=int(rng.integers(0, 2)) << 9, pwm=(int(rng.integers(0, 9)),),
                              message=int(rng.random() < 0.3) * 100)
                batch.append(last)
            else:                            # a hold, as StepSamples makes it
                batch.append(model_mod.ev.Sample(**{**last.__dict__, "t_ms": t, "message": 0}))
        held += fast._holds(batch)
        fast.add_samples(batch)
        slow.add_samples(batch)
        for a, b in zip((fast.time, *fast._value_buffers()), (slow.time, *slow._value_buffers())):
            assert a.total == b.total and np.array_equal(a.views(), b.views())
        assert (fast.active_outputs, fast.active_inputs, fast.proc_values, fast.running,
                fast.last_sample, fast.version) == (slow.active_outputs, slow.active_inputs,
                                                     slow.proc_values, slow.running,
                                                     slow.last_sample, slow.version)
    assert held > 10                         # the short way was taken


def test_ring_buffer_repeats_its_last_row_across_the_wrap():
    rb = RingBuffer(5, 2)
    rb.repeat_last(3)                        # nothing written yet: nothing to repeat
    assert rb.total == 0
    rb.extend(np.array([[1, 10], [2, 20], [3, 30]]))
    rb.repeat_last(4)
    assert rb.total == 7 and rb.view(0).tolist() == [3, 3, 3, 3, 3]
    assert rb.views(last=6).shape == (2, 5)
    rb.append((4, 40))
    rb.repeat_last(12)                       # more than the capacity
    assert rb.total == 20 and rb.view(1).tolist() == [40] * 5 and rb.latest().tolist() == [4, 40]


def test_model_keeps_messages_bounded():
    m = RunModel(capacity=10, messages=50)
    rows = m.add_events([ev.Message(t, 131, None, 1, 2, "M03") for t in range(120)]
                        + [ev.Print(5, 20000, 1, "M03")])
    assert len(rows) == 120 and rows[0].name == "PLC_MESSAGE_SPINDLE_TURNING"
    assert len(m.messages) <= 50 and m.messages[-1].t_ms == 119
    assert m.message_times == pytest.approx([r.t_ms / 1000 for r in m.messages])


def test_signed_words_are_bits():
    m = RunModel(capacity=10)
    m.add_samples([sample(0, outputs=-(1 << 31))])     # bit 31 as a signed word
    assert m.active_outputs == {31}


# ------------------------------------------------------------------ pin names
def test_pin_names_from_defines():
    ins, outs = pin_names_from_defines({
        "INPUT_PROBE": ("3", None), "INPUT_HOME_X": "0x0 // comment", "OUTPUT_SPINDLE": 0,
        "OUTPUT_PLASMA": ("4",), "OUTPUT_TORCH": "4", "PWM_SPINDLE_SPEED": "0",
        "INPUT_BAD": "FOO", "OUTPUT_HUGE": "100000"})
    assert ins == {3: "INPUT_PROBE", 0: "INPUT_HOME_X"}
    assert outs == {0: "OUTPUT_SPINDLE", 4: "OUTPUT_PLASMA / OUTPUT_TORCH"}
    ins, outs = pin_names_from_header("#define INPUT_A 7 // x\n  #  define OUTPUT_B (2)\n")
    assert ins == {7: "INPUT_A"} and outs == {2: "OUTPUT_B"}
    ins, outs = default_pin_names()
    assert ins[3] == "INPUT_PROBE" and outs[0] == "OUTPUT_SPINDLE"


def test_pin_names_from_a_compiled_project_file():
    from plcbuilder.api import compile_source
    r = compile_source("#include pins.h\nmain() { portset(OUTPUT_MIST); exit(99); }", "M07.plc")
    ins, outs = pin_names_from_defines(r.symbols.defines)
    assert outs[2] == "OUTPUT_MIST" and ins[9] == "INPUT_CYCLE_START"


# ------------------------------------------------------------------ docks
def test_docks_have_names_and_render(qtbot, panels, fake, tmp_path):
    docks = panels.docks()
    names = [d.objectName() for d in docks]
    assert len(set(names)) == len(panels.DOCKS) == 8 and all(names)
    assert [d.windowTitle() for d in docks] == [title for _k, title, _n in panels.DOCKS]
    fake.sig_samples.emit([sample(t, proc=70, outputs=t & 1, pwm=(t,), axes=(t, 2 * t))
                           for t in range(500)])
    fake.sig_events.emit([ev.Message(100, 131, "PLC_MESSAGE_SPINDLE_TURNING", 0, 0, "M03")])
    panels.tick()
    for d in docks:
        img = d.grab()
        assert not img.isNull() and img.width() > 50
    # only visible docks redraw; a hidden one catches up when shown
    panels.dock("axes").hide()
    before = panels.axes.frames
    fake.sig_samples.emit([sample(500, axes=(1, 1))])
    panels.tick()
    assert panels.axes.frames == before and panels.lanes.frames > 0
    panels.dock("axes").show()
    panels.tick()
    assert panels.axes.frames == before + 1


def test_lanes_follow_pins_and_the_context_menu(qtbot, panels, fake):
    panels.set_pin_names({9: "INPUT_CYCLE_START"}, {0: "OUTPUT_SPINDLE", 5: "OUTPUT_LUBE"})
    fake.sig_samples.emit([sample(t, outputs=1 if t > 10 else 0) for t in range(50)])
    panels.tick()
    lanes = panels.lanes
    assert lanes.lanes() == [("outputs", 0)]
    assert lanes.y_labels() == ["OUT 0  OUTPUT_SPINDLE"]
    menu = lanes.build_menu(("outputs", 0))
    texts = [a.text() for a in menu.actions()]
    assert texts[0] == "Remove lane OUT 0  OUTPUT_SPINDLE"
    sub = [a.menu() for a in menu.actions() if a.text() == "Add output lane"][0]
    pick = [a for a in sub.actions() if a.text() == "5  OUTPUT_LUBE"][0]
    pick.trigger()
    panels.tick()
    assert lanes.lanes() == [("outputs", 0), ("outputs", 5)]
    menu.actions()[0].trigger()                       # remove OUT 0
    panels.tick()
    assert lanes.lanes() == [("outputs", 5)]
    lanes.pin_lane("inputs", 9)
    panels.tick()
    assert lanes.y_labels() == ["OUT 5  OUTPUT_LUBE", "IN 9  INPUT_CYCLE_START"]
    lanes.reset_lanes()
    panels.tick()
    assert lanes.lanes() == [("outputs", 0)]


def test_lane_under_the_mouse(qtbot, panels, fake):
    fake.sig_samples.emit([sample(t, outputs=0b11 if t > 10 else 0) for t in range(50)])
    panels.tick()
    lanes = panels.lanes
    vb = lanes.plot.getViewBox()
    top = lanes.widget.mapFromScene(vb.mapViewToScene(QtCore.QPointF(-0.01, 2.0)))
    low = lanes.widget.mapFromScene(vb.mapViewToScene(QtCore.QPointF(-0.01, 0.5)))
    assert lanes._lane_at(top) == ("outputs", 0)
    assert lanes._lane_at(low) == ("outputs", 1)


def test_follow_stops_when_the_user_pans(qtbot, panels, fake):
    fake.sig_samples.emit([sample(t) for t in range(1500)])
    panels.tick()
    tb = panels.timebase
    assert tb.follow
    t0, t1 = panels.lanes.visible_span()
    assert t0 == pytest.approx(0.0) and t1 == pytest.approx(10.0)   # filling a 10 s window
    vb = panels.lanes.plot.getViewBox()
    vb.sigRangeChangedManually.emit([True, False])
    assert not tb.follow and not panels.proc.toolbar.follow.isChecked()
    panels.lanes.toolbar.follow.click()
    assert tb.follow and panels.axes.toolbar.follow.isChecked()
    combo = panels.analog.toolbar.window
    combo.setCurrentIndex(combo.findText("1 s"))
    combo.activated.emit(combo.currentIndex())
    assert tb.window == 1.0
    panels.tick()
    t0, t1 = panels.lanes.visible_span()
    assert t1 == pytest.approx(1.499) and t0 == pytest.approx(0.499)


def test_clear_forgets_samples_and_messages(qtbot, panels, fake):
    fake.sig_samples.emit([sample(t, pwm=(5,)) for t in range(100)])
    fake.sig_events.emit([ev.Message(10, 101, None, 0, 0, "M03")])
    panels.tick()
    assert panels.proc.messages.rowCount() == 1 and panels.analog._curves
    panels.proc.toolbar.findChildren(QtWidgets.QToolButton)[-1].click()   # Clear
    panels.tick()
    assert len(panels.model) == 0 and panels.proc.messages.rowCount() == 0
    assert not panels.analog._curves


def test_log_rows_and_fault_click(qtbot, panels, fake):
    fake.sig_events.emit([
        ev.Started(0, "M03", "hardware", 5),
        ev.Print(3, 20000, 42, "M03"),
        ev.Print(4, 20007, -1, "M03"),
        ev.Message(5, -15, "PLC_MESSAGE_ERR_PROBING", 0, 0, "M03"),
        ev.Fault(6, "M03", "M03.plc", 12, "division by zero"),
        ev.Ended(6, "M03", "hardware", -1, None, 0),
        ev.Ended(9, "M88", "hardware", 7, "plc_exit_probe_error", 3),
        ev.Note(10, "jog watchdog stopped the jog", "warning"),
    ])
    fake.sig_error.emit("start: no procedure named 'X'")
    panels.tick()
    texts = [r[TEXT] for r in panels.log.rows.rows()]
    # the register is in every print row (issue 13, defect 9), the first one's too
    assert "register 20000 = 42" in texts and "register 20007 = -1" in texts
    assert "PLC_MESSAGE_ERR_PROBING (-15)  command=0 parameter=0" in texts
    assert any(t.startswith("M88 ended: exit plc_exit_probe_error (7)") and "probe" in t
               for t in texts)
    assert "start: no procedure named 'X'" in texts
    rows = panels.log.fault_rows()
    assert len(rows) == 1
    # filters
    panels.log.kind_buttons["print"].click()
    assert panels.log.proxy.rowCount() == len(texts) - 2
    panels.log.kind_buttons["print"].click()
    panels.log.search.setText("probing")
    assert panels.log.proxy.rowCount() == 1
    panels.log.search.clear()
    # a click on the fault opens its line; on anything else, nothing
    view = panels.log.view
    got = []
    panels.sig_open_location.connect(lambda f, line: got.append((f, line)))
    other = view.visualRect(panels.log.proxy.index(1, 3)).center()
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=other)
    assert got == []
    rect = view.visualRect(panels.log.proxy.index(panels.log.fault_rows()[0], 3))
    with qtbot.waitSignal(panels.sig_open_location, timeout=2000) as blocker:
        qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    assert blocker.args == ["M03.plc", 12]


def test_reply_messages_are_decoded():
    from plcbuilder.ide.panels.model import decode_message
    assert decode_message(1100, 120, 12000) == \
        "to myCNC: PLC_MESSAGE_SPINDLE_SPEED_CHANGED (120), parameter 12000"
    assert decode_message(131, 0, 0) == ""
    row = event_row(ev.Message(5, 1100, "PLCCMD_REPLY_TO_MYCNC", 120, 0, "M05"))
    assert row[TEXT] == ("PLCCMD_REPLY_TO_MYCNC (1100)  to myCNC: "
                         "PLC_MESSAGE_SPINDLE_SPEED_CHANGED (120), parameter 0")


def test_fault_without_file_names_the_procedure():
    row = event_row(ev.Fault(1, "M05", None, 3, "call depth over 16"))
    assert row[CATEGORY] == "fault" and row[-2:] == ("M05.plc", 3)
    assert event_row(ev.Fault(1, "M05", None, None, "x"))[-1] is None
    assert event_row({"type": "future", "t_ms": 5})[CATEGORY] == "note"
    assert event_row(object()) is None


def test_searching_a_long_log_waits_for_a_pause_in_typing(qtbot, panels, fake):
    """Each key typed into the search of a long log filtered every row (60-120
    ms a key at 20,000 rows): past SEARCH_AT_ONCE_ROWS the search runs once
    typing pauses (or at Enter); a short log is searched at each key."""
    from plcbuilder.ide.panels.log import SEARCH_AT_ONCE_ROWS
    from plcbuilder.ide.typing_pause import PAUSE_MS as SEARCH_PAUSE_MS
    log = panels.log
    runs = []
    refilter = log._refilter
    log._refilter = lambda change: (runs.append(1), refilter(change))
    fake.sig_events.emit([ev.Print(t, 20000, t, "SW") for t in range(SEARCH_AT_ONCE_ROWS + 500)])
    panels.tick()
    n = log.proxy.rowCount()
    assert n == SEARCH_AT_ONCE_ROWS + 500
    for text in ("1", "12", "123"):
        log.search.setText(text)
    assert runs == [] and log.proxy.rowCount() == n          # typing: nothing filtered yet
    qtbot.waitUntil(lambda: runs == [1], timeout=SEARCH_PAUSE_MS * 10)
    assert log.proxy.rowCount() == sum("123" in f"register 20000 = {t}"
                                       for t in range(SEARCH_AT_ONCE_ROWS + 500))
    log.search.setText("1234")
    qtbot.keyClick(log.search, Qt.Key.Key_Return)            # Enter: at once
    assert runs == [1, 1] and log.proxy.rowCount() == 1      # (register 20000 = 1234)
    qtbot.wait(SEARCH_PAUSE_MS * 2)
    assert runs == [1, 1]                                    # (and not again after the pause)


def test_the_first_telemetry_is_drawn_at_once_and_said_once(qtbot, panels, fake):
    """The panels' first telemetry is drawn at the event loop's next turn, not
    a frame later (the start waits for it: issue 26.5), and sig_live says so
    once; later samples wait for the redraw timer's frame as before."""
    said = []
    panels.sig_live.connect(lambda: said.append(True))
    assert not panels.live
    fake.sig_samples.emit([sample(1, outputs=1)])
    assert panels.timer.isActive() and panels.timer.interval() == 0
    qtbot.waitUntil(lambda: panels.live, timeout=1000)
    assert said == [True]
    fake.sig_samples.emit([sample(2, outputs=3)])
    assert panels.timer.interval() == panels.frame_ms
    qtbot.wait(3 * panels.frame_ms)
    assert said == [True]


def test_log_is_bounded(qtbot, panels, fake):
    panels.log.rows.limit = 1000
    fake.sig_events.emit([ev.Print(t, 20000, t, "SW") for t in range(2500)])
    panels.tick()
    n = panels.log.rows.rowCount()
    assert 0 < n <= 1000
    assert panels.log.rows.row(n - 1)[TEXT] == "register 20000 = 2499"


def test_inputs_panel_sends_and_shows(qtbot, panels, fake):
    panels.set_pin_names({3: "INPUT_PROBE", 9: "INPUT_CYCLE_START"}, {})
    inputs = panels.inputs
    assert inputs.shown_pins() == [3, 9]
    assert not inputs.button(3).isEnabled() or not inputs.grid_host.isEnabled()
    fake.connected = True
    fake.sig_connected.emit("127.0.0.1:1")
    panels.dock("inputs").raise_()
    qtbot.mouseClick(inputs.button(3), Qt.MouseButton.LeftButton)
    assert fake.calls[-1] == ("input", 3, 1)
    assert inputs.button(3).isChecked()                # shown as asked until a sample says
    fake.sig_samples.emit([sample(1, inputs=1 << 3, adc=(0, 0, 512))])
    panels.tick()
    assert inputs.button(3).isChecked() and inputs.readings[2].text() == "512"
    # the slider and the box show what the channel reads, not 0 (issue 13, defect 9)
    assert inputs.sliders[2].value() == 512 and inputs.spins[2].value() == 512
    fake.sig_samples.emit([sample(2, inputs=1 << 3, adc=(0, 0, 1200))])
    panels.tick()
    assert inputs.sliders[2].value() == 1200 and inputs.spins[2].value() == 1200
    inputs.show_all.setChecked(True)
    assert len(inputs.shown_pins()) == 64
    inputs.filter.setText("probe")
    assert inputs.shown_pins() == [3]
    inputs.spins[1].setValue(1000)
    assert fake.calls[-1] == ("adc", 1, 1000)
    fake.sig_disconnected.emit("the controller process was killed (SIGKILL)")
    assert not inputs.grid_host.isEnabled()
    assert "Disconnected" in panels.proc.status.text()


def test_typing_into_the_pin_filter_lays_the_grid_out_once(qtbot, panels, monkeypatch):
    """A key typed into the inputs' filter with every pin shown took a
    quarter of a second: each toggle shown into the working grid made it ask
    every other toggle for its size (64 x 64). The grid is laid out once."""
    from plcbuilder.ide.panels.inputs import PinToggle
    inputs = panels.inputs
    panels.dock("inputs").raise_()
    inputs.show_all.setChecked(True)
    qtbot.waitUntil(lambda: inputs.button(63).isVisible())
    asked = []                      # (its size hint and its paint measure its chrome)
    chrome = PinToggle._chrome
    monkeypatch.setattr(PinToggle, "_chrome", lambda self: (asked.append(self), chrome(self))[1])
    for text in ("i", "in", ""):
        asked.clear()
        inputs.filter.setText(text)
        QtWidgets.QApplication.processEvents()
        assert len(inputs.shown_pins()) == 64
        assert len(asked) <= 8 * 64, (text, len(asked))     # (was 64 x 64 x 2)
    assert all(inputs.button(p).isVisible() for p in range(64))
    rows = sorted({inputs.button(p).y() for p in range(64)})
    assert len(rows) == 32                      # two columns, laid out


def test_a_pin_toggle_made_when_first_shown_shows_the_pin_as_it_is(qtbot, panels, fake):
    """A pin's toggle is made when it is first shown (64 of them, most never
    shown, took a tenth of the panel's making); one made later shows the
    newest sample and the pin's force all the same."""
    panels.set_pin_names({3: "INPUT_PROBE"}, {})
    inputs = panels.inputs
    assert 3 in inputs.buttons and len(inputs.buttons) < 64
    on = sample(1)                          # pins 40 and 41 on (bits 8 and 9 of word 1)
    fake.sig_samples.emit([ev.Sample(**{**on.__dict__, "inputs": (0, 0x300) + (0,) * 6})])
    panels.tick()
    panels.set_forces([{"target": "in 41", "value": 0}])
    inputs.filter.setText("input 4")
    inputs.show_all.setChecked(True)
    assert inputs.shown_pins() == [4] + list(range(40, 50))
    panels.tick()
    assert inputs.button(40).isChecked() and inputs.button(40).isVisible()
    # forced off: what the program reads, with the force's mark
    assert not inputs.button(41).isChecked() and inputs.button(41).property("forced") == "true"
    assert not inputs.button(42).isChecked()
    never_shown = set(range(64)) - set(default_pin_names()[0]) - {3, 4} - set(range(40, 50))
    assert never_shown and not never_shown & set(inputs.buttons)
    with pytest.raises(KeyError):
        inputs.button(64)


@pytest.mark.parametrize("target", ["huazhong", "mycnc"])
@pytest.mark.parametrize("width", [420, 300])
def test_the_inputs_grid_fits_its_dock_with_long_pin_names(qtbot, panels, target, width):
    """Wave 2 of issue 26: on a Huazhong project the bank-bit labels
    (``10  X1.2 INPUT_LIMIT_MIN_X``) made the Inputs dock's grid wider than the
    dock, with a horizontal scroll bar. The labels fit: the bank bit is the
    head (not the pin number too), and a name too long for its toggle goes
    without its INPUT_ and is shortened in its middle; the tooltip and the
    filter have it whole."""
    panels.set_target(target)
    panels.set_pin_names(default_pin_names()[0], {})
    dock = panels.dock("inputs")
    dock.setFloating(True)
    dock.resize(width, 500)
    dock.show()
    qtbot.waitExposed(dock)
    QtWidgets.QApplication.processEvents()
    inputs = panels.inputs
    scroll = inputs.findChild(QtWidgets.QScrollArea)
    assert not scroll.horizontalScrollBar().isVisible()
    assert inputs.grid_host.width() <= scroll.viewport().width()
    shown = inputs.shown_pins()
    assert 10 in shown
    b = inputs.button(10)
    head = "X1.2" if target == "huazhong" else "10"
    assert b.text() == f"{head}  INPUT_LIMIT_MIN_X"          # the whole label
    assert "INPUT_LIMIT_MIN_X" in b.toolTip() and "Input 10" in b.toolTip()
    for pin in shown:
        t = inputs.button(pin)
        assert t.isVisible() and t.geometry().right() <= inputs.grid_host.width()
        drawn = t.shown_text()
        assert drawn.startswith(t.head)
        assert t.fontMetrics().horizontalAdvance(drawn) <= t.width() - t._chrome()
    if width == 300:                     # too narrow for the whole name: shortened
        assert b.shown_text() != b.text() and b.shown_text().endswith("_X")
    inputs.filter.setText("limit_min_x")
    assert inputs.shown_pins() == [10]
    if target == "huazhong":
        inputs.filter.setText("x1.2")
        assert inputs.shown_pins() == [10]


def test_watch_panel_orders_and_follows(qtbot, panels, fake):
    fake.connected = True
    fake.sig_state.emit(ControllerStatus(t_ms=10, running="M03", software=(), proc=70), 0)
    panels._poll_variables()
    assert fake.calls[-1] == ("variables",)
    assert "Running M03" in panels.proc.status.text()
    assert "plc_proc_spindle (70)" in panels.proc.status.text()
    vars_ = {"M03": {"eparam": 1, "proc": 70, "timer": 0, "vexit": 0, "message": 0,
                     "var00": 0, "var01": 0, "speed": 5, "count": 3},
             "M05": {"eparam": 0, "proc": 0, "x": 1}}
    fake.sig_variables.emit(vars_)
    w = panels.watch
    names = [w.table.item(r, 0).text() for r in range(w.table.rowCount())]
    assert names == ["speed", "count", "eparam", "proc", "timer", "vexit", "message"]
    w.show_regs.setChecked(True)
    assert w.table.rowCount() == 9
    vars_["M03"]["count"] = 4
    fake.sig_variables.emit(vars_)
    assert w.table.item(1, 1).text() == "4" and w.table.item(1, 2).text() == "0x00000004"
    assert w.table.item(1, 1).background().color().name() == "#fff2b3"   # changed
    w.procedure.setCurrentText("M05")
    w.procedure.activated.emit(w.procedure.currentIndex())
    assert w.current == "M05" and not w.follow.isChecked()
    assert w.value("x") == 1


# ------------------------------------------------------------- redraw cost
def _count_set_data(monkeypatch):
    import pyqtgraph as pg
    calls = []
    orig = pg.PlotDataItem.setData

    def counting(self, *a, **k):
        calls.append(self)
        return orig(self, *a, **k)
    monkeypatch.setattr(pg.PlotDataItem, "setData", counting)
    return calls


def test_the_redraw_timer_stops_when_nothing_changes(qtbot, panels, fake):
    fake.sig_samples.emit([sample(t, outputs=t & 1, running=None) for t in range(100)])
    assert panels.timer.isActive()                    # samples woke it
    panels.tick()
    f0 = panels.lanes.frames
    assert f0 >= 1
    panels.tick()                                     # nothing new: it stops
    assert not panels.timer.isActive()
    # nothing runs and the new samples only advance time: nothing redraws
    fake.sig_samples.emit([sample(t, outputs=1, running=None) for t in range(100, 200)])
    assert panels.timer.isActive()
    frames = [p.frames for p in panels.time_panels]
    panels.tick()
    assert [p.frames for p in panels.time_panels] == frames
    assert panels.lanes.moves == 0 and not panels.timer.isActive()
    # and the timer stays stopped while the event loop idles
    ticks = panels.ticks
    qtbot.wait(200)
    assert panels.ticks == ticks
    # a value that changes redraws, even while nothing runs
    fake.sig_samples.emit([sample(200, outputs=0, running=None)])
    panels.tick()
    assert panels.lanes.frames == f0 + 1


def test_only_time_advancing_moves_the_curves_without_set_data(qtbot, panels, fake,
                                                             monkeypatch):
    panels.timebase.set_window(1.0)
    fake.sig_samples.emit([sample(t, outputs=t & 1, pwm=(t,)) for t in range(0, 2000, 10)])
    fake.sig_samples.emit([sample(2000, outputs=1, pwm=(99,))])
    panels.tick()
    calls = _count_set_data(monkeypatch)
    frames = panels.lanes.frames
    fake.sig_samples.emit([sample(t, outputs=1, pwm=(99,)) for t in range(2001, 2100)])
    panels.lanes._last_move = panels.analog._last_move = 0.0
    panels.tick()
    assert panels.lanes.frames == frames and panels.lanes.moves == 1
    assert panels.lanes.offset == pytest.approx(panels.lanes.visible_span()[1])
    assert calls == []                                 # no setData: the curves moved
    # past the horizon the curves are drawn again
    fake.sig_samples.emit([sample(t, outputs=1, pwm=(99,)) for t in range(2100, 3000, 10)])
    panels.lanes._last_move = 0.0
    panels.tick()
    assert panels.lanes.frames == frames + 1 and calls


def test_hidden_docks_do_not_redraw(qtbot, panels, fake, monkeypatch):
    fake.sig_samples.emit([sample(t, outputs=t & 1, pwm=(t,), axes=(t,)) for t in range(100)])
    panels.tick()
    for d in panels.docks():
        d.hide()
    calls = _count_set_data(monkeypatch)
    before = [(p.frames, p.moves) for p in panels.time_panels]
    for k in range(5):
        fake.sig_samples.emit([sample(t, outputs=t & 1, pwm=(t,), axes=(t,))
                               for t in range(100 + 50 * k, 150 + 50 * k)])
        panels.tick()
    assert [(p.frames, p.moves) for p in panels.time_panels] == before and calls == []
    assert not panels.timer.isActive()
    fake.connected = True
    fake.sig_state.emit(ControllerStatus(t_ms=10, running="M03", software=(), proc=70), 0)
    panels._poll_variables()
    assert ("variables",) not in fake.calls              # the watch is hidden
    panels.dock("outputs").show()                      # shown: it catches up
    assert panels.timer.isActive()
    panels.tick()
    assert panels.lanes.frames == before[1][0] + 1
    panels.dock("watch").show()
    assert fake.calls[-1] == ("variables",)


def test_lanes_are_one_curve_that_keeps_every_edge(qtbot, panels, fake):
    panels.timebase.set_window(0.3)
    dock = panels.dock("outputs")
    dock.setFloating(True)
    dock.resize(1500, 400)
    qtbot.waitUntil(lambda: panels.lanes.plot.getViewBox().width() > 1000)
    fake.sig_samples.emit([sample(t, outputs=(t & 1) | ((t >> 1) & 1) << 1 | 1 << 5)
                           for t in range(300)])
    panels.tick()
    lanes = panels.lanes
    assert lanes.lanes() == [("outputs", 0), ("outputs", 1), ("outputs", 5)]
    x, y = lanes.merged_data("outputs")
    items = [i for i in lanes.plot.listDataItems() if isinstance(i, type(lanes._items["outputs"]))]
    assert len(items) == 4      # outputs, virtual outputs, inputs, variables: one curve each
    t = np.arange(300) / 1000.0 - lanes.offset
    for pin, period in ((0, 1), (1, 2)):
        base = lanes._lane_y[("outputs", pin)]
        mine = (y >= base - 0.01) & (y <= base + 1.01)
        lx, ly = x[mine], y[mine] - base
        edges = np.arange(period, 300, period)        # every change of the output
        assert len(lx) == 2 + 2 * len(edges)
        assert np.allclose(lx[1:-1:2], t[edges]) and np.allclose(lx[2:-1:2], t[edges])
        want = (edges // period) & 1
        assert np.array_equal(ly[2:-1:2], want) and np.array_equal(ly[1:-1:2], 1 - want)
    steady = lanes._lane_y[("outputs", 5)]
    assert np.count_nonzero(np.isclose(y, steady + 1)) == 2   # held high, start to end
    # a lane with more edges than pixels keeps the first and last of each pixel column
    from plcbuilder.ide.panels.plots.lanes import lane_path
    n = 20000
    words = np.zeros((8, n), dtype=np.uint32)
    words[0] = np.arange(n) & 1
    tt = np.arange(n) / 1000.0
    x, y, connect, (x0, x1, y0) = lane_path(words, [0], [0.0], tt, tt[-1], 0.0, 20.0 / 500)
    assert len(x) == 6 and not connect[-1] and connect[:-1].all()
    # every column shows both levels: one filled block from the first edge to the last
    assert np.allclose(x0, [tt[1]]) and np.allclose(x1, [tt[-1]]) and np.allclose(y0, [0.0])
    # a lane dense in places: blocks there, every edge elsewhere
    words[0] = np.where((np.arange(n) // 5000) % 2 == 0, np.arange(n) & 1, (np.arange(n) >> 9) & 1)
    x, y, connect, (x0, x1, y0) = lane_path(words, [0], [0.0], tt, tt[-1], 0.0, 20.0 / 500)
    assert len(x0) == 2                                # the two dense stretches
    sparse = (tt > x1[0]) & (tt < x0[1])
    edges = np.nonzero(np.diff(words[0]))[0] + 1
    for e in edges[sparse[edges]]:                     # every edge between them is in the path
        assert np.count_nonzero(np.isclose(x, tt[e])) == 2


def test_a_forced_redraw_of_unchanged_samples_keeps_the_curves_data(qtbot, panels, fake):
    """Redraw only what changed: a curve whose samples, window and x origin are
    the ones it was drawn from gets no new data; a new sample redraws them."""
    fake.sig_samples.emit([sample(t, outputs=t & 1, pwm=(t % 7, 3)) for t in range(200)])
    panels.tick()
    analog, lanes = panels.analog, panels.lanes
    assert analog.refresh(force=True) and lanes.refresh(force=True)
    items = [*analog._curves.values(), lanes._items["outputs"]]
    assert len(items) == 3                   # pwm01, pwm02 and the outputs' lanes
    calls = []
    for item in items:
        real = item.setData
        item.setData = lambda *a, _real=real, _item=item, **k: (calls.append(_item),
                                                                _real(*a, **k))
    before = [np.array(i.getOriginalDataset()[1]) for i in items]
    analog.refresh(force=True)
    lanes.refresh(force=True)
    assert calls == []
    assert all(np.array_equal(b, i.getOriginalDataset()[1]) for b, i in zip(before, items))
    fake.sig_samples.emit([sample(200, outputs=1, pwm=(5, 3))])
    panels.tick()
    analog.refresh(force=True)
    lanes.refresh(force=True)
    assert set(map(id, calls)) == set(map(id, items))
    x, y = analog._curves[0].getOriginalDataset()
    assert y[-1] == 5 and len(x) == len(y)
