"""The IDE's dialogs: procedure and header names and go to line (:mod:`.files`),
the start-procedure picker and connect to a controller (:mod:`.run`), a new
project (:mod:`.new_project`), preferences (:mod:`.preferences`) and issue a
code to the controller (:mod:`.issue_code`). The find/replace bar is
:mod:`plcbuilder.ide.editor.find_bar`.

Each modal dialog has a ``get_…`` class method that runs it and returns the
result, or None when cancelled; tests drive the widgets and call
``accept()`` through a patched ``exec``.
"""

from plcbuilder._support.lazy import lazy_names

# Each name loads its module when first used (PEP 562): the main window opens
# without building the dialogs' classes (nor Qt's for them).
_WHERE = {"GoToLineDialog": "files", "HeaderNameDialog": "files",
          "ProcedureNameDialog": "files", "check_procedure_name": "files",
          "PreferencesDialog": "preferences", "ConnectDialog": "run", "StartDialog": "run",
          "NewProjectDialog": "new_project", "IssueCodeDialog": "issue_code"}


__getattr__ = lazy_names(__name__, _WHERE)


def __dir__() -> list:
    return sorted(set(globals()) | set(__all__))


__all__ = ["ConnectDialog", "GoToLineDialog", "HeaderNameDialog", "IssueCodeDialog",
           "NewProjectDialog",
           "PreferencesDialog", "ProcedureNameDialog", "StartDialog", "check_procedure_name"]
