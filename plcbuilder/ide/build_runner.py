"""Build All on a worker thread: :class:`BuildRunner` runs
:func:`plcbuilder.project.build.build_project` and reports progress and the
result through signals (the Build Output panel, :mod:`.build_panel`, shows
them)."""

from __future__ import annotations

import threading
import time
from typing import Optional

from PySide6.QtCore import QObject, Signal


class BuildRunner(QObject):
    """Runs Build All on a worker thread (one build at a time)."""

    sig_started = Signal()
    """A build started."""

    sig_progress = Signal(int, int, str)
    """(done, total, procedure name) after each procedure."""

    sig_finished = Signal(object)
    """The BuildResult, or an Exception when the build could not run."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self._thread: Optional[threading.Thread] = None
        self.started_at = 0.0
        self.elapsed = 0.0

    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self, project) -> bool:
        """Start building; False when a build is running already."""
        if self.running():
            return False
        from plcbuilder.project.build import build_project
        self.started_at = time.perf_counter()
        self.sig_started.emit()

        def work():
            try:
                result = build_project(project, lambda d, t, n: self.sig_progress.emit(d, t, n))
            except Exception as exc:  # noqa: BLE001 - reported in the panel
                result = exc
            self.elapsed = time.perf_counter() - self.started_at
            try:
                self.sig_finished.emit(result)
            except RuntimeError:
                pass

        self._thread = threading.Thread(target=work, name="plcbuilder-build", daemon=True)
        self._thread.start()
        return True

    def wait(self, timeout: float = 30) -> None:
        if self._thread is not None:
            self._thread.join(timeout)
