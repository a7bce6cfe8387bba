"""Issue 23 point 16: nothing in the plots covers or cuts another thing, in a
dock as narrow as the right-hand ones are at first start (408 × 260 px):
legends sit in their plot's title row, not over the curves; titles fit; an
empty lanes plot has no numbers on its lane axis ("1.0" was cut at its top);
message labels are not cut at the left edge. (The time axis' first label:
test_panels_idle.py.)"""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from PySide6 import QtGui, QtWidgets  # noqa: E402

from plcbuilder.controller import events as ev  # noqa: E402
from plcbuilder.ide.panels.model import RunModel  # noqa: E402
from plcbuilder.ide.panels.plots import AnalogPanel, AxesPanel, LanesPanel, ProcPanel, TimeBase  # noqa: E402
from tests.ide.test_panels import sample  # noqa: E402

SIZE = (408, 260)


def _shown(qtbot, panel_class, samples, events=()):
    model = RunModel(4000)
    panel = panel_class(model, TimeBase())
    qtbot.addWidget(panel)
    panel.resize(*SIZE)
    panel.show()
    qtbot.waitExposed(panel)
    model.add_samples(samples)
    rows = model.add_events(events)
    if rows and hasattr(panel, "add_messages"):
        panel.add_messages(rows)
    for _ in range(3):
        panel.refresh(force=True, moving=False)
        QtWidgets.QApplication.processEvents()
    return panel


def _clear_of_view(legend, plot) -> bool:
    return not legend.sceneBoundingRect().intersects(plot.vb.sceneBoundingRect())


def test_the_analog_legends_never_cover_the_curves(qtbot):
    samples = [sample(t, pwm=(12000,), adc=(1200 - t // 10, 2048)) for t in range(3000)]
    p = _shown(qtbot, AnalogPanel, samples)
    for legend, plot in ((p.out_legend, p.out_plot), (p.in_legend, p.in_plot)):
        assert legend.items and legend.isVisible()
        assert _clear_of_view(legend, plot), (legend.sceneBoundingRect(),
                                              plot.vb.sceneBoundingRect())
        title = plot.titleLabel.item.mapRectToScene(plot.titleLabel.item.boundingRect())
        assert not legend.sceneBoundingRect().intersects(title)


def test_the_axes_legends_and_titles_fit(qtbot):
    samples = [sample(t, axes=(t, 2 * t, -t // 2), vel=(10, 20, -5)) for t in range(3000)]
    p = _shown(qtbot, AxesPanel, samples)
    assert [lab.text for _s, lab in p.pos_legend.items] == ["X", "Y", "Z"]
    assert _clear_of_view(p.pos_legend, p.pos_plot)
    assert p.vel_plot.legend is None          # the same colours: named once, above
    # the XY path's title is drawn whole inside its plot
    t = p.xy.titleLabel
    drawn = t.item.mapRectToScene(t.item.boundingRect())
    assert p.xy.sceneBoundingRect().contains(drawn), (drawn, p.xy.sceneBoundingRect())
    # the left axes' labels do not run into each other
    a, b = (plot.getAxis("left").label for plot in (p.pos_plot, p.vel_plot))
    assert not a.sceneBoundingRect().intersects(b.sceneBoundingRect())


def test_an_empty_lanes_plot_has_no_numbers_on_its_lane_axis(qtbot):
    p = _shown(qtbot, LanesPanel, [])
    ax = p.plot.getAxis("left")
    levels = ax.tickValues(*p.plot.vb.viewRange()[1], ax.height()) if ax._tickLevels is None \
        else ax._tickLevels
    assert all(not level for level in (levels or [[]])) if ax._tickLevels is not None \
        else not any(v for _s, v in levels)


def test_message_labels_are_not_cut_at_the_left_edge(qtbot):
    samples = [sample(t, proc=70 if t > 50 else 0) for t in range(0, 10_000)]
    msgs = [ev.Message(t, 120, None, 0, 0, "M03") for t in range(40, 10_000, 700)]
    p = _shown(qtbot, ProcPanel, samples, msgs)
    vb = p.plot.vb.sceneBoundingRect()
    shown = [lab for lab in p._labels if lab.isVisible()]
    assert shown
    for lab in shown:
        r = lab.textItem.mapRectToScene(lab.textItem.boundingRect())
        assert r.left() >= vb.left() - 1, (lab.toPlainText(), r, vb)
    # following moves them left: one that would leave at the edge is hidden, not cut
    left = p.plot.vb.viewRange()[0][0]
    first = min(lab.pos().x() for lab in shown)
    p.shift(-(first - left) - 0.2)           # the leftmost marker past the edge
    QtWidgets.QApplication.processEvents()
    for lab in p._labels:
        if lab.isVisible():
            r = lab.textItem.mapRectToScene(lab.textItem.boundingRect())
            assert r.left() >= vb.left() - 1


def test_the_xy_paths_tick_numbers_do_not_run_together(qtbot):
    samples = [sample(t, axes=(10000 + t % 7, 10000, 0)) for t in range(3000)]
    p = _shown(qtbot, AxesPanel, samples)
    p.xy_widget.grab()
    ax = p.xy.getAxis("bottom")
    lo, hi = ax.range
    fm = QtGui.QFontMetricsF(ax.style["tickFont"])
    for spacing, values in ax.tickValues(lo, hi, ax.width())[:1]:
        texts = ax.tickStrings(values, 1.0, spacing)
        px = [(v - lo) * ax.width() / (hi - lo) for v in values]
        for (x0, t0), (x1, t1) in zip(zip(px, texts), zip(px[1:], texts[1:])):
            assert x1 - x0 >= (fm.horizontalAdvance(t0) + fm.horizontalAdvance(t1)) / 2 + 4, \
                texts


@pytest.mark.parametrize("offset", [227097.0, 3.0])
def test_the_time_axis_numbers_do_not_run_together_late_in_a_session(qtbot, offset):
    """A capture 63 hours into a session, shown in the plots' narrow dock: the
    time axis read "2270972270972270972270 98" (six-digit times a tenth of a
    second apart). Its ticks are spaced for their numbers' width."""
    from plcbuilder.ide.panels import style
    w = style.plot_widget(style.time_axis(), menu=False)
    style.style_plot(w.getPlotItem(), bottom="time (s)", bottom_units=None)
    qtbot.addWidget(w)
    w.resize(300, 160)
    w.show()
    qtbot.waitExposed(w)
    ax = w.getPlotItem().getAxis("bottom")
    ax.set_offset(offset)
    w.getPlotItem().setXRange(0.0, 0.6, padding=0)
    w.grab()
    lo, hi = ax.range
    fm = QtGui.QFontMetricsF(ax.style["tickFont"])
    levels = ax.tickValues(lo, hi, ax.width())
    spacing, values = levels[0]
    assert len(values) >= 2
    texts = ax.tickStrings(values, 1.0, spacing)
    px = [(v - lo) * ax.width() / (hi - lo) for v in values]
    for (x0, t0), (x1, t1) in zip(zip(px, texts), zip(px[1:], texts[1:])):
        assert x1 - x0 >= (fm.horizontalAdvance(t0) + fm.horizontalAdvance(t1)) / 2 + 4, texts
