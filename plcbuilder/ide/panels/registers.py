"""The registers of a target's program (docs/targets.md), under the watch.

On Huazhong the banks' elements that are not 0 (X, Y and R bytes; G, F, P and
B words), on TG Motion the TGM_Data words that are not 0, then how many times
each procedure was called and the budget overruns; on TG Motion also the
oscilloscope: the signals the project picks (``[tgmotion] oscilloscope``) and
their newest samples. The values come with the
watch's poll of the controller (``sig_target_report``); the X and Y bits are also
the input and output lanes, named X0.0 … and Y0.0 … (:func:`bit_names`).
Hidden on myCNC.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

Qt = QtCore.Qt

#: banks shown as 16-bit words (the others are bytes)
WORD_BANKS = frozenset({"G", "F", "P", "B"})


def bit_names(pins: int, bank: str, names: dict[int, str]) -> dict[int, str]:
    """Lane names of the Huazhong target: pin 8n+b is ``X<n>.<b>`` (the seed's
    notation), followed by the pin's own name where it has one."""
    out = {}
    for pin in range(pins):
        label = f"{bank}{pin // 8}.{pin % 8}"
        own = names.get(pin)
        out[pin] = f"{label} {own}" if own else label
    return out


class _WrappedLabel(QtWidgets.QLabel):
    """A word-wrapped label in a splitter section: its minimum height is what
    its text needs at its width (a splitter does not ask a label's height for
    its width, and squeezed the calls line under the registers' table)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setWordWrap(True)

    def _fit(self) -> None:
        if self.width() > 0:
            need = self.heightForWidth(self.width())
            if need > 0 and need != self.minimumHeight():
                self.setMinimumHeight(need)

    def setText(self, text: str) -> None:  # noqa: N802 - Qt's name
        if text != self.text():
            super().setText(text)
            self._fit()

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        if event.size().width() != event.oldSize().width():
            self._fit()


class RegistersPanel(QtWidgets.QWidget):
    """A table of the target's non-zero registers, and the calls."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.title = QtWidgets.QLabel()
        self.table = QtWidgets.QTableWidget(0, 3)
        self.table.setObjectName("registers")
        self.table.setHorizontalHeaderLabels(["Register", "Value", "Hex"])
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.calls = _WrappedLabel()
        self.calls.setObjectName("calls")
        self.scope_title = QtWidgets.QLabel()
        self.scope = QtWidgets.QTableWidget(0, 0)          # TG Motion's oscilloscope
        self.scope.setObjectName("oscilloscope")
        self.scope.verticalHeader().hide()
        self.scope.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        # the registers over the oscilloscope: a splitter's two sections
        from plcbuilder.ide.panels.watch import GripSplitter, SplitterSizes, small_minimum
        regs = QtWidgets.QWidget()
        rl = QtWidgets.QVBoxLayout(regs)
        rl.setContentsMargins(0, 4, 0, 0)
        rl.addWidget(self.title)
        rl.addWidget(self.table, 1)
        rl.addWidget(self.calls)
        self.scope_part = QtWidgets.QWidget()
        sl = QtWidgets.QVBoxLayout(self.scope_part)
        sl.setContentsMargins(0, 4, 0, 0)
        sl.addWidget(self.scope_title)
        sl.addWidget(self.scope, 1)
        self.scope_part.hide()
        self.split = GripSplitter(Qt.Orientation.Vertical)
        self.split.setObjectName("registersSplitter")
        self.split.addWidget(regs)
        self.split.addWidget(self.scope_part)
        small_minimum(self.table)
        small_minimum(self.scope)
        self.sizes = SplitterSizes(self.split, "registers")
        self.sizes.watch(self.scope_part)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.split)
        self.report: dict = {}
        self.hide()

    def set_report(self, report: dict) -> None:
        """Show a target's report (``{}``: hide, as on myCNC)."""
        self.report = dict(report)
        if not report:
            self.hide()
            return
        self.show()
        self.title.setText(f"<b>{report.get('target_profile', '')}</b> registers (not 0)")
        rows = []
        for bank, values in report.get("registers", {}).items():
            for index, value in values.items():
                rows.append((f"{bank}[{index}]", int(value), bank in WORD_BANKS))
        self.table.setRowCount(len(rows))
        for r, (name, value, word) in enumerate(rows):
            digits = 4 if word else (2 if value >= 0 and value < 256 else 8)
            for c, text in enumerate((name, str(value), f"0x{value & 0xFFFFFFFF:0{digits}x}")):
                item = self.table.item(r, c)
                if item is None:
                    item = QtWidgets.QTableWidgetItem()
                    self.table.setItem(r, c, item)
                item.setText(text)
        calls = report.get("calls", {})
        text = "calls: " + ", ".join(f"{n} {k}" for n, k in calls.items())
        over = report.get("budget_overruns", {})
        if over:
            text += "<br><span style='color:#b35c00'>over budget: " + ", ".join(
                f"{n} {k}×" for n, k in over.items()) + "</span>"
        self.calls.setText(text)
        self._show_scope(report.get("oscilloscope"))

    def _show_scope(self, scope) -> None:
        """The oscilloscope's newest samples, newest first: time (µs), cycle,
        then one column a signal (hidden without an oscilloscope)."""
        self.scope_part.setVisible(bool(scope))
        if not scope:
            return
        signals = [str(s) for s in scope.get("signals", [])]
        self.scope_title.setText(f"<b>oscilloscope</b>: {int(scope.get('samples', 0))} "
                                 f"samples of {', '.join(signals) or 'no signal'}")
        headers = ["t (µs)", "cycle", *signals]
        self.scope.setColumnCount(len(headers))
        self.scope.setHorizontalHeaderLabels(headers)
        rows = [list(r) for r in reversed(scope.get("last", []))]
        self.scope.setRowCount(len(rows))
        for r, row in enumerate(rows):
            for c in range(len(headers)):
                item = self.scope.item(r, c)
                if item is None:
                    item = QtWidgets.QTableWidgetItem()
                    self.scope.setItem(r, c, item)
                item.setText(str(row[c]) if c < len(row) else "")
