"""The inputs panel: a toggle per input pin, a slider per ADC channel.

A toggle shows the input as the controller last reported it; clicking it asks
the controller to set the pin by hand (which overrides the machine's own wiring
of that pin from then on). Sliders send their value when they stop moving.

With a controller that forces (SPEC §6: ``force_by_hand``), a click or a slider
*forces* the input or ADC channel: it shows as forced (the force icon and an
orange frame, the reading in orange) until released from the right-click menu
or the Forces panel, which gives the machine's wiring back.
"""

from __future__ import annotations

import time

from PySide6 import QtCore, QtGui, QtWidgets

from plcbuilder.ide.panels.model import RunModel

Qt = QtCore.Qt
Signal = QtCore.Signal

ADC_MAX = 4095
PENDING_S = 0.6        # a clicked pin shows the asked state this long before a sample wins

_TOGGLE_STYLE = """
QToolButton { border: 1px solid palette(mid); border-radius: 3px; padding: 3px 6px;
              background: palette(button); color: palette(button-text); text-align: left; }
QToolButton:hover { border-color: #6a9bd1; }
QToolButton:checked { background: #3c9d4b; border-color: #2f7d3b; color: #ffffff; }
QToolButton:disabled { color: palette(mid); background: palette(window); }
QToolButton[forced="true"] { border: 2px solid #c75a00; }
"""
FORCED_STYLE = "color: #c75a00; font-weight: bold;"


class PinToggle(QtWidgets.QToolButton):
    """An input pin's toggle. Its label is a head (the pin's number, or on the
    Huazhong target its bank bit, ``X0.4``) and the pin's name; where the dock
    is too narrow for the whole label the name goes without its ``INPUT_``
    and then, if still too long, is shortened in its middle (``LIMI…MIN_X``:
    names of a family differ at their ends); the tooltip has it whole.
    ``text()`` is always the whole label."""

    #: characters of the name a toggle keeps at its narrowest (besides "…")
    MIN_NAME_CHARS = 3
    #: what a shortened name goes without first (every pin here is an input)
    PREFIX = "INPUT_"

    def __init__(self, parent=None):
        super().__init__(parent)
        self.head = ""
        self.name = ""

    def set_label(self, head: str, name: str) -> None:
        self.head, self.name = head, name
        self.setText(f"{head}  {name}" if name else head)

    def shown_text(self) -> str:
        """The label as drawn at the toggle's width now."""
        fm = self.fontMetrics()
        text = self.text()
        room = self.width() - self._chrome()
        if not self.name or fm.horizontalAdvance(text) <= room:
            return text
        head = f"{self.head}  "
        room -= fm.horizontalAdvance(head)
        name = self.name
        if name[:len(self.PREFIX)].upper() == self.PREFIX and len(name) > len(self.PREFIX):
            name = name[len(self.PREFIX):]          # INPUT_HOME_X: HOME_X says it here
        return head + fm.elidedText(name, Qt.TextElideMode.ElideMiddle, max(0, room))

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802 - Qt override
        hint = super().minimumSizeHint()
        if not self.name:
            return hint
        fm = self.fontMetrics()
        least = self._chrome() + fm.horizontalAdvance(
            f"{self.head}  {self.name[:self.MIN_NAME_CHARS]}…")
        return QtCore.QSize(min(hint.width(), least), hint.height())

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt override
        opt = QtWidgets.QStyleOptionToolButton()
        self.initStyleOption(opt)
        opt.text = self.shown_text()
        painter = QtWidgets.QStylePainter(self)
        painter.drawComplexControl(QtWidgets.QStyle.ComplexControl.CC_ToolButton, opt)

    def _chrome(self) -> int:
        """The width the toggle takes besides its text (frame, padding, icon)."""
        return super().sizeHint().width() - self.fontMetrics().horizontalAdvance(self.text())


class InputsPanel(QtWidgets.QWidget):
    """Toggles for the input pins and sliders for the ADC channels."""

    sig_set_input = Signal(int, int)
    """A toggle asks for input pin (int) to be set to value (0/1)."""

    sig_set_adc = Signal(int, int)
    """A slider asks for ADC channel (int) to read value (int)."""

    sig_force = Signal(str, int)
    """Force a target (``in N`` or ``adc N``) to a value."""

    sig_release = Signal(str, str)
    """Release a target (``in N`` or ``adc N``): ``keep`` or ``restore``."""

    COLUMNS = 2

    def __init__(self, model: RunModel, pins: int = 64, adc_channels: int = 8, parent=None,
                 names: dict[int, str] | None = None, bank: str | None = None):
        super().__init__(parent)
        self.model = model
        self.pins = pins
        self.names: dict[int, str] = {}
        #: the bank whose bits the pins are (Huazhong: "X", pin 8n+b is X<n>.<b>), or None
        self.bank: str | None = None
        #: the pins' toggles made so far: a pin's is made when it is first
        #: shown or asked for (:meth:`button`); most pins are never shown
        self.buttons: dict[int, PinToggle] = {}
        self._pending: dict[int, tuple[int, float]] = {}
        self._adc_pending: dict[int, tuple[int, float]] = {}   # ADC values asked, not yet read
        self._drawn = -1
        self.force_by_hand = False          # clicks and sliders force (the controller can)
        self.forced_pins: dict[int, int] = {}
        self.forced_adc: dict[int, int] = {}

        top = QtWidgets.QHBoxLayout()
        top.setContentsMargins(4, 2, 4, 2)
        self.show_all = QtWidgets.QCheckBox("Show unnamed pins")
        self.show_all.setToolTip("Also show the input pins that pins.h does not name")
        self.show_all.toggled.connect(self._relayout)
        self.filter = QtWidgets.QLineEdit()
        self.filter.setPlaceholderText("Filter pins…")
        self.filter.setClearButtonEnabled(True)
        self.filter.textChanged.connect(self._relayout)
        top.addWidget(self.filter, 1)
        top.addWidget(self.show_all)

        self.grid_host = QtWidgets.QWidget()
        self.grid = QtWidgets.QGridLayout(self.grid_host)
        self.grid.setContentsMargins(4, 4, 4, 4)
        self.grid.setSpacing(3)
        self.grid_host.setStyleSheet(_TOGGLE_STYLE)
        pins_box = QtWidgets.QGroupBox("Input pins")
        pl = QtWidgets.QVBoxLayout(pins_box)
        pl.setContentsMargins(2, 2, 2, 2)
        pl.addLayout(top)
        pl.addWidget(self.grid_host)
        pl.addStretch(1)

        adc_box = QtWidgets.QGroupBox("ADC channels")
        ag = QtWidgets.QGridLayout(adc_box)
        ag.setContentsMargins(6, 4, 6, 4)
        ag.setHorizontalSpacing(8)
        self.sliders: list[QtWidgets.QSlider] = []
        self.spins: list[QtWidgets.QSpinBox] = []
        self.readings: list[QtWidgets.QLabel] = []
        for ch in range(adc_channels):
            label = QtWidgets.QLabel(f"ADC{ch}" + (f" (adc0{ch + 1})" if ch < 2 else ""))
            s = QtWidgets.QSlider(Qt.Orientation.Horizontal)
            s.setRange(0, ADC_MAX)
            s.setToolTip(f"Set ADC{ch} by hand (sent when you let go)")
            spin = QtWidgets.QSpinBox()
            spin.setRange(-99999, 99999)
            # as wide as a 5-digit value needs (a 32-bit one scrolls in the box):
            # ten digits nobody types neither widen the dock nor squeeze the slider
            spin.setFixedWidth(spin.sizeHint().width())
            spin.setRange(-(1 << 31), (1 << 31) - 1)
            spin.setKeyboardTracking(False)
            spin.setToolTip(f"ADC{ch} value to set (Enter sends it)")
            reading = QtWidgets.QLabel("–")
            reading.setMinimumWidth(48)
            reading.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
            reading.setToolTip(f"What ADC{ch} reads now")
            s.valueChanged.connect(lambda v, sp=spin: (sp.blockSignals(True), sp.setValue(v),
                                                       sp.blockSignals(False)))
            s.sliderReleased.connect(lambda ch=ch, sl=s: self._adc(ch, sl.value()))
            for w in (s, reading, label):
                w.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
                w.customContextMenuRequested.connect(
                    lambda pos, ch=ch, w=w: self.adc_menu(ch).exec(w.mapToGlobal(pos)))
            s.actionTriggered.connect(
                lambda action, ch=ch, sl=s: self._slider_action(ch, sl, action))
            spin.valueChanged.connect(lambda v, ch=ch: self._spin_changed(ch, v))
            ag.addWidget(label, ch, 0)
            ag.addWidget(s, ch, 1)
            ag.addWidget(spin, ch, 2)
            ag.addWidget(reading, ch, 3)
            self.sliders.append(s)
            self.spins.append(spin)
            self.readings.append(reading)
        ag.setColumnStretch(1, 1)
        self.sig_set_adc.connect(
            lambda ch, v: self._adc_pending.__setitem__(ch, (v, time.monotonic() + PENDING_S)))

        body = QtWidgets.QWidget()
        bl = QtWidgets.QVBoxLayout(body)
        bl.setContentsMargins(2, 2, 2, 2)
        bl.addWidget(pins_box)
        bl.addWidget(adc_box)
        bl.addStretch(1)
        scroll = QtWidgets.QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(body)
        scroll.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(scroll)
        self.set_pin_names(names or {}, bank)

    # ------------------------------------------------------------------ API
    def set_pin_names(self, inputs: dict[int, str], bank: str | None = None) -> None:
        """The pins' names (pins.h); with ``bank`` (the Huazhong target's "X")
        each pin is labelled by its bank bit (X0.4) rather than its number,
        and every pin is shown (each has a name there: its bit)."""
        self.names = dict(inputs)
        self.bank = bank
        self.show_all.setVisible(bank is None)
        self._relayout()

    def shown_pins(self) -> list[int]:
        text = self.filter.text().strip().lower()
        pins = [p for p in range(self.pins) if p in self.names or self.bank is not None
                or self.show_all.isChecked() or not self.names]
        if text:
            pins = [p for p in pins if text in self._tooltip(p).lower()]
        return pins

    def button(self, pin: int) -> PinToggle:
        """Pin ``pin``'s toggle (made now if it was not)."""
        b = self.buttons.get(pin)
        if b is None:
            if not 0 <= pin < self.pins:
                raise KeyError(pin)
            b = self.buttons[pin] = self._make_button(pin)
        return b

    def _make_button(self, pin: int) -> PinToggle:
        b = PinToggle(self.grid_host)
        b.hide()
        b.setCheckable(True)
        b.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding,
                        QtWidgets.QSizePolicy.Policy.Fixed)
        b.clicked.connect(lambda checked: self._clicked(pin, checked))
        b.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        b.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        b.customContextMenuRequested.connect(
            lambda pos: self.pin_menu(pin).exec(b.mapToGlobal(pos)))
        if pin in self.forced_pins:
            self._mark_forced(b, True)
        self._drawn = -1                    # (its state: the next refresh)
        return b

    @staticmethod
    def _mark_forced(b: PinToggle, forced: bool) -> None:
        from plcbuilder.ide.icons import icon
        b.setProperty("forced", "true" if forced else "false")
        b.setIcon(icon("debug-force") if forced else QtGui.QIcon())
        b.style().unpolish(b)
        b.style().polish(b)

    def set_forces(self, forces: list) -> None:
        """What is forced (``[{target, value}]``): forced pins and channels are marked."""
        pins, adc = {}, {}
        for f in forces:
            kind, _, n = str(f.get("target", "")).partition(" ")
            if n.isdigit() and kind in ("in", "adc"):
                (pins if kind == "in" else adc)[int(n)] = int(f.get("value") or 0)
        self.forced_pins, self.forced_adc = pins, adc
        for pin, b in self.buttons.items():
            forced = pin in pins
            if (b.property("forced") == "true") != forced:
                self._mark_forced(b, forced)
        for ch, lab in enumerate(self.readings):
            lab.setStyleSheet(FORCED_STYLE if ch in adc else "")
            lab.setToolTip(f"ADC{ch} is forced at {adc[ch]} (right-click to release)"
                           if ch in adc else f"What ADC{ch} reads now")
        self._drawn = -1
        self.refresh()

    def pin_menu(self, pin: int) -> QtWidgets.QMenu:
        """The right-click menu of an input pin (built, not shown: tests use it)."""
        t = f"in {pin}"
        return self._force_menu(t, pin in self.forced_pins, self.grid_host.isEnabled(), (
            ("Force On (1)", "force_on", lambda: self.sig_force.emit(t, 1)),
            ("Force Off (0)", "force_off", lambda: self.sig_force.emit(t, 0))))

    def adc_menu(self, ch: int) -> QtWidgets.QMenu:
        """The right-click menu of an ADC channel."""
        t = f"adc {ch}"
        return self._force_menu(t, ch in self.forced_adc, self.spins[ch].isEnabled(), (
            (f"Force ADC{ch} at {self.spins[ch].value()}", "force",
             lambda: self.sig_force.emit(t, self.spins[ch].value())),))

    def _force_menu(self, t: str, forced: bool, enabled: bool, forces) -> QtWidgets.QMenu:
        """A menu of ``forces`` ((text, object name, slot) each) and the two
        releases of target ``t`` (only while it is forced); nothing is enabled
        while ``enabled`` is not."""
        menu = QtWidgets.QMenu(self)
        for text, obj, slot, on in (
                *((text, obj, slot, True) for text, obj, slot in forces),
                ("Release (keep the value)", "release_keep",
                 lambda: self.sig_release.emit(t, "keep"), forced),
                ("Release (back to the machine's wiring)", "release_restore",
                 lambda: self.sig_release.emit(t, "restore"), forced)):
            act = menu.addAction(text, slot)
            act.setObjectName(obj)
            act.setEnabled(on and enabled)
        return menu

    def set_enabled(self, on: bool) -> None:
        self.grid_host.setEnabled(on)
        for w in self.sliders + self.spins:
            w.setEnabled(on)

    def refresh(self) -> None:
        """Show the newest sample's input and ADC values."""
        if self.model.version == self._drawn and not self._pending and not self._adc_pending:
            return
        self._drawn = self.model.version
        s = self.model.last_sample
        if s is None:
            return
        now = time.monotonic()
        for pin, b in self.buttons.items():
            w = pin // 32
            v = (int(s.inputs[w]) >> (pin % 32)) & 1 if w < len(s.inputs) else 0
            if pin in self.forced_pins:       # what the program reads (also while halted)
                v = 1 if self.forced_pins[pin] else 0
            pend = self._pending.get(pin)
            if pend is not None:
                if pend[0] == v or now > pend[1]:
                    del self._pending[pin]
                else:
                    v = pend[0]
            if b.isChecked() != bool(v):
                b.setChecked(bool(v))
        for ch, lab in enumerate(self.readings):
            if ch < len(s.adc):
                forced = ch in self.forced_adc
                value = int(self.forced_adc[ch]) if forced else int(s.adc[ch])
                text = f"{value} F" if forced else str(value)
                if lab.text() != text:
                    lab.setText(text)
                self._show_adc(ch, value, now)

    # -------------------------------------------------------------- private
    def _show_adc(self, ch: int, value: int, now: float) -> None:
        """The slider and the box follow what the channel reads (the machine
        may drive it), except while the user is at them or a value they set is
        on its way."""
        pend = self._adc_pending.get(ch)
        if pend is not None:
            if pend[0] != value and now <= pend[1]:
                return
            del self._adc_pending[ch]
        slider, spin = self.sliders[ch], self.spins[ch]
        if slider.isSliderDown() or spin.hasFocus():
            return
        if spin.value() != value:
            spin.blockSignals(True)
            spin.setValue(value)
            spin.blockSignals(False)
        clamped = max(0, min(ADC_MAX, value))
        if slider.value() != clamped:
            slider.blockSignals(True)
            slider.setValue(clamped)
            slider.blockSignals(False)

    def _label(self, pin: int) -> tuple[str, str]:
        """(head, name) of a pin's toggle."""
        name = self.names.get(pin, "")
        if self.bank is not None:
            return f"{self.bank}{pin // 8}.{pin % 8}", name
        return f"{pin:>2}", name or f"input {pin}"

    def _tooltip(self, pin: int) -> str:
        """The pin, whole: its number, bank bit and name."""
        head, name = self._label(pin)
        if self.bank is not None:
            return f"Input {pin} ({head}{', ' + name if name else ''})"
        return f"Input {pin}" + (f" ({name})" if pin in self.names else "")

    def _relayout(self, *args) -> None:
        # the grid lays out once, at the end: shown one by one into a working
        # grid, each toggle made it ask every other for its size (a key typed
        # into the filter took a quarter of a second with the 64 pins shown)
        self.grid.setEnabled(False)
        try:
            self._fill_grid()
        finally:
            self.grid.setEnabled(True)
            self.grid.invalidate()
            self.grid.activate()

    def _fill_grid(self) -> None:
        while self.grid.count():
            item = self.grid.takeAt(0)
            w = item.widget()
            if w is not None:
                w.hide()
        made = len(self.buttons)
        for i, pin in enumerate(self.shown_pins()):
            b = self.button(pin)
            b.set_label(*self._label(pin))
            b.setToolTip(self._tooltip(pin)
                         + (": click to force it (right-click to release it)"
                            if self.force_by_hand else
                            ": click to set it by hand (overrides the machine's wiring)"))
            self.grid.addWidget(b, i // self.COLUMNS, i % self.COLUMNS)
            b.show()
        if len(self.buttons) != made:
            self.refresh()                  # the toggles just made show their pins

    def _clicked(self, pin: int, checked: bool) -> None:
        value = 1 if checked else 0
        self._pending[pin] = (value, time.monotonic() + PENDING_S)
        if self.force_by_hand:
            self.sig_force.emit(f"in {pin}", value)
        else:
            self.sig_set_input.emit(pin, value)

    def _adc(self, ch: int, value: int) -> None:
        if self.force_by_hand:
            self.sig_force.emit(f"adc {ch}", int(value))
        else:
            self.sig_set_adc.emit(ch, int(value))

    def _slider_action(self, ch: int, slider: QtWidgets.QSlider, action: int) -> None:
        # keyboard / page clicks (not drags) send at once; drags send on release
        if not slider.isSliderDown():
            QtCore.QTimer.singleShot(0, lambda: self._adc(ch, slider.value()))

    def _spin_changed(self, ch: int, value: int) -> None:
        s = self.sliders[ch]
        s.blockSignals(True)
        s.setValue(max(0, min(ADC_MAX, value)))
        s.blockSignals(False)
        self._adc(ch, value)
