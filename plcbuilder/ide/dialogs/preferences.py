"""The Preferences dialog."""

from __future__ import annotations

from typing import Optional

from PySide6.QtGui import QFontDatabase
from PySide6.QtWidgets import (QCheckBox, QComboBox, QDialog, QFontComboBox,
                               QFormLayout, QSpinBox, QTabWidget, QVBoxLayout, QWidget)

from plcbuilder.ide.dialogs.common import ok_cancel
from plcbuilder.ide.settings import Preferences


class PreferencesDialog(QDialog):
    def __init__(self, parent=None, prefs: Preferences = Preferences()):
        super().__init__(parent)
        self.setWindowTitle("Preferences")
        self.original = prefs
        lay = QVBoxLayout(self)
        tabs = QTabWidget(self)
        lay.addWidget(tabs)
        # editor
        ed = QWidget()
        f = QFormLayout(ed)
        self.font_combo = QFontComboBox(ed)
        self.font_combo.setFontFilters(QFontComboBox.FontFilter.MonospacedFonts)
        family = prefs.font_family or QFontDatabase.systemFont(
            QFontDatabase.SystemFont.FixedFont).family()
        self.font_combo.setCurrentText(family)
        self.size_spin = QSpinBox(ed)
        self.size_spin.setRange(6, 48)
        self.size_spin.setValue(prefs.font_size)
        self.size_spin.setSuffix(" pt")
        self.tab_spin = QSpinBox(ed)
        self.tab_spin.setRange(1, 16)
        self.tab_spin.setValue(prefs.tab_width)
        self.theme_combo = QComboBox(ed)
        self.theme_combo.addItem("Light", "light")
        self.theme_combo.addItem("Dark", "dark")
        self.theme_combo.setCurrentIndex(max(0, self.theme_combo.findData(prefs.theme)))
        self.ws_box = QCheckBox("Show whitespace", ed)
        self.ws_box.setChecked(prefs.show_whitespace)
        self.guides_box = QCheckBox("Indentation guides", ed)
        self.guides_box.setChecked(prefs.indent_guides)
        self.ac_box = QCheckBox("Complete while typing", ed)
        self.ac_box.setChecked(prefs.autocomplete)
        self.ac_spin = QSpinBox(ed)
        self.ac_spin.setRange(1, 10)
        self.ac_spin.setValue(prefs.autocomplete_threshold)
        self.ac_spin.setSuffix(" characters")
        self.hover_box = QCheckBox("Hover help", ed)
        self.hover_box.setChecked(prefs.hover)
        f.addRow("Font:", self.font_combo)
        f.addRow("Size:", self.size_spin)
        f.addRow("Tab width:", self.tab_spin)
        f.addRow("Theme:", self.theme_combo)
        f.addRow("", self.ws_box)
        f.addRow("", self.guides_box)
        f.addRow("", self.ac_box)
        f.addRow("Complete after:", self.ac_spin)
        f.addRow("", self.hover_box)
        tabs.addTab(ed, "Editor")
        # files and build
        fb = QWidget()
        g = QFormLayout(fb)
        self.autosave_spin = QSpinBox(fb)
        self.autosave_spin.setRange(1, 600)
        self.autosave_spin.setValue(prefs.autosave_seconds)
        self.autosave_spin.setSuffix(" s")
        self.autosave_spin.setToolTip("unsaved changes are copied to a recovery folder this "
                                      "often, and offered back after a crash")
        self.reload_box = QCheckBox("Reload files changed on disk when they have no unsaved changes", fb)
        self.reload_box.setChecked(prefs.reload_unmodified)
        self.save_build_box = QCheckBox("Save all files before Build All and Run Tests "
                                        "without asking", fb)
        self.save_build_box.setToolTip("Off: Build All and Run Tests ask first when an editor "
                                       "has unsaved changes (they never run on files the "
                                       "editors do not show)")
        self.save_build_box.setChecked(prefs.save_before_build)
        self.build_upload_box = QCheckBox("Build All before Upload", fb)
        self.build_upload_box.setChecked(prefs.build_before_upload)
        self.reopen_box = QCheckBox("Open the last project on start", fb)
        self.reopen_box.setChecked(prefs.open_last_project)
        self.first_frame_box = QCheckBox("Show the project at once while the IDE opens", fb)
        self.first_frame_box.setToolTip(
            "On: a plain window shows the project's tree and file (read-only) while the IDE's "
            "window is made, then gives way to it. Off: nothing shows until the IDE's window "
            "is made, which is then ready a little sooner")
        self.first_frame_box.setChecked(prefs.first_frame)
        g.addRow("Recovery autosave every:", self.autosave_spin)
        g.addRow("", self.reload_box)
        g.addRow("", self.save_build_box)
        g.addRow("", self.build_upload_box)
        g.addRow("", self.reopen_box)
        g.addRow("", self.first_frame_box)
        tabs.addTab(fb, "Files && Build")
        self.buttons = ok_cancel(self, lay)
        self.setMinimumWidth(460)

    def preferences(self) -> Preferences:
        return self.original.with_changes(
            font_family=self.font_combo.currentFont().family(),
            font_size=self.size_spin.value(), tab_width=self.tab_spin.value(),
            theme=self.theme_combo.currentData(), show_whitespace=self.ws_box.isChecked(),
            indent_guides=self.guides_box.isChecked(), autocomplete=self.ac_box.isChecked(),
            autocomplete_threshold=self.ac_spin.value(), hover=self.hover_box.isChecked(),
            autosave_seconds=self.autosave_spin.value(),
            reload_unmodified=self.reload_box.isChecked(),
            save_before_build=self.save_build_box.isChecked(),
            build_before_upload=self.build_upload_box.isChecked(),
            open_last_project=self.reopen_box.isChecked(),
            first_frame=self.first_frame_box.isChecked())

    @classmethod
    def get_preferences(cls, parent=None, prefs: Preferences = Preferences()) -> Optional[Preferences]:
        dlg = cls(parent, prefs)
        if dlg.exec() == QDialog.DialogCode.Accepted:
            return dlg.preferences()
        return None
