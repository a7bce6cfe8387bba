"""The IDE's dialogs: procedure and header names and go to line (:mod:`.files`),
the start-procedure picker and connect to a controller (:mod:`.run`), and
preferences (:mod:`.preferences`). The find/replace bar is
:mod:`plcbuilder.ide.editor.find_bar`.

Each modal dialog has a ``get_…`` class method that runs it and returns the
result, or None when cancelled; tests drive the widgets and call
``accept()`` through a patched ``exec``.
"""

from plcbuilder.ide.dialogs.files import (GoToLineDialog, HeaderNameDialog, ProcedureNameDialog,
                                          check_procedure_name)
from plcbuilder.ide.dialogs.preferences import PreferencesDialog
from plcbuilder.ide.dialogs.run import ConnectDialog, StartDialog

__all__ = ["ConnectDialog", "GoToLineDialog", "HeaderNameDialog", "PreferencesDialog",
           "ProcedureNameDialog", "StartDialog", "check_procedure_name"]
