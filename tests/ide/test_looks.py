"""The visual defects of issue 13, point 10: the default layout gives the tree
and the bottom docks room, the proc axis names do not overlap, a message's
meaning is in view, legends leave the curves free, the name check shows
__HANDLER_INIT whole, squiggles cover a whole word, the speed list drops
below its box."""

import numpy as np
from PySide6.QtCore import Qt

from plcbuilder.api import Diagnostic, Severity, Span
from plcbuilder.api import Kind
from plcbuilder.ide import dialogs
from plcbuilder.ide.editor import IND_ERROR, CodeEditor
from plcbuilder.ide.panels.plots.timebase import YFit
from tests.ide.test_docks_fit import prompts_off, runwin  # noqa: F401 - fixtures
from tests.ide.test_panels import fake, panels, sample  # noqa: F401 - fixtures


def test_the_default_layout_gives_the_tree_and_the_bottom_docks_room(runwin, qtbot):  # noqa: F811
    w, _conn = runwin
    w.resize(1360, 860)
    w.reset_layout()
    qtbot.wait(50)
    tree = w.project_dock
    assert tree.width() >= 280                               # was 230: "coolant off (mist a…"
    assert w.problems_dock.height() >= 225                   # was 206: 6-7 rows
    rows = w.problems.tree.viewport().height() // max(1, w.problems.tree.fontMetrics().height())
    assert rows >= 8


def test_close_proc_states_do_not_overlap_on_the_axis(panels, fake, qtbot):  # noqa: F811
    fake.sig_samples.emit([sample(t, proc=32 if t < 50 else 33) for t in range(100)])
    proc_dock = panels.dock("proc")
    proc_dock.show()
    proc_dock.raise_()
    panels.proc.widget.resize(400, 160)
    panels.tick()
    qtbot.waitUntil(lambda: bool(panels.proc.shown_y_labels()), timeout=3000)
    shown = panels.proc.shown_y_labels()
    assert set(panels.proc.y_labels()) >= set(shown)
    close = [t for t in shown if t.endswith("(32)") or t.endswith("(33)")]
    assert close == ["plc_proc_probing (33)"]                # the newest state's name wins


def test_a_messages_meaning_is_in_view(panels):  # noqa: F811
    table = panels.proc.table
    model = table.model()
    headers = [model.headerData(i, Qt.Orientation.Horizontal) for i in range(model.columnCount())]
    assert headers.index("Meaning") == headers.index("Message") + 1
    right = sum(table.columnWidth(i) for i in range(headers.index("Meaning")))
    assert right < 430                                         # starts inside a 430 px dock


def test_legends_leave_the_curves_free(qtbot):
    import pyqtgraph as pg
    w = pg.PlotWidget()
    qtbot.addWidget(w)
    w.resize(500, 260)
    w.show()
    plot = w.getPlotItem()
    legend = plot.addLegend(offset=(8, 8), colCount=2)
    for i in range(6):
        plot.plot([0, 1], [0, 1000], name=f"PWM{i} (pwm0{i + 1})")
    qtbot.wait(30)
    fit = YFit(plot)
    fit.legend = legend
    fit.fit([np.array([0.0, 1000.0])])
    lo, hi = fit.range
    share = fit.legend_share()
    assert share > 0.1
    assert 1000 <= hi - (hi - lo) * share + 1e-6              # the data stays under the legend


def test_an_empty_legend_draws_no_stray_box(qtbot):
    """The PWM / DAC plot showed a small empty frame in its corner until the first
    channel changed: a legend without rows paints nothing; with one, its frame."""
    import pyqtgraph as pg
    from PySide6 import QtGui

    from plcbuilder.ide.panels import style

    w = pg.PlotWidget()
    qtbot.addWidget(w)
    plot = w.getPlotItem()
    title = style.legend(plot, columns=2)          # the plot's own: in its title row
    assert style.legend(plot) is title and plot.legend is title
    lg = style.new_legend(plot, (-8, 8))            # a legend in the view (a comparison's key)
    w.resize(400, 300)
    w.show()
    qtbot.waitExposed(w)
    qtbot.waitUntil(lambda: lg.boundingRect().width() > 0)    # laid out: an 18 px square

    def painted() -> bool:
        img = QtGui.QImage(64, 64, QtGui.QImage.Format.Format_ARGB32)
        img.fill(0)
        p = QtGui.QPainter(img)
        lg.paint(p)
        p.end()
        return any(img.pixel(x, y) for x in range(64) for y in range(64))

    assert not painted()
    curve = plot.plot([0, 1], [0, 1], name="PWM0")            # a named curve: a legend row
    lg.addItem(curve, "PWM0")
    assert len(lg.items) == 1 and painted()
    lg.removeItem(curve)                                      # (a compared trace's row goes)
    assert not painted()
    # the title row's legend has the row, and no frame of its own to draw
    assert len(title.items) == 1 and not title.frame


def test_the_name_check_shows_underscores_whole(qtbot):
    dlg = dialogs.ProcedureNameDialog(None, title="New Procedure", kind=Kind.SOFTWARE)
    qtbot.addWidget(dlg)
    dlg.show()
    qtbot.waitExposed(dlg)
    dlg.name_edit.setText("a b")
    qtbot.wait(20)
    err = dlg.error
    assert "__HANDLER_INIT" in err.text()
    assert err.textFormat() == Qt.TextFormat.PlainText
    assert err.height() >= err.heightForWidth(err.width())    # no wrapped line cut off
    lay = dlg.layout()
    assert dlg.height() >= lay.totalHeightForWidth(dlg.width())


def test_a_point_squiggle_covers_the_word(qtbot):
    ed = CodeEditor()
    qtbot.addWidget(ed)
    ed.set_text("main()\n{\n  a = 1000   // the ; is missing\n  exit(99);\n};\n")
    d = Diagnostic(Severity.ERROR, "syntax", "expected ';' after '1000'",
                   Span("<t>", 3, 11, 3, 11))                # just after "1000"
    ed.set_diagnostics([d])
    (start, end), = ed.indicator_ranges(IND_ERROR)
    assert ed.byte_range_text(start, end) == "1000"


def test_the_speed_list_drops_below_its_box(runwin, qtbot):  # noqa: F811
    w, _conn = runwin
    combo = w.run_actions.speed_combo
    combo.setEnabled(True)
    combo.setCurrentIndex(combo.findText("Max"))
    combo.showPopup()
    popup = combo.view().window()
    qtbot.waitUntil(popup.isVisible, timeout=2000)
    top = popup.mapToGlobal(popup.rect().topLeft()).y()
    bottom_of_box = combo.mapToGlobal(combo.rect().bottomLeft()).y()
    combo.hidePopup()
    assert top >= bottom_of_box - 1


def test_main_is_highlighted_once_its_brace_is_typed_below_it(qtbot):
    """``main()`` under a comment line, its ``{`` typed on the next line: the
    definition's colour comes at once, not at the next full restyle."""
    from plcbuilder.ide import highlighter as hl
    ed = CodeEditor()
    qtbot.addWidget(ed)
    ed.resize(600, 300)
    ed.show()
    qtbot.waitExposed(ed)
    ed.set_text("// a comment\nmain()\n")
    ed.highlighter.style_to(ed.length())
    assert ed.styleAt(ed.position_of(2, 1)) != hl.S_FUNCTION       # no brace yet
    ed.insertText(ed.length(), "{\n  exit(99);\n};\n")
    ed.highlighter.style_to(ed.length())                            # what Scintilla asks
    assert ed.styleAt(ed.position_of(2, 1)) == hl.S_FUNCTION
