"""The project folder model (``model``), Build All (``build``) and ``plcbuilder
new`` (``new``).

Build All's names load on first use (PEP 562): opening a project (``model``)
does not load the compiler.
"""

from __future__ import annotations

from plcbuilder._support.lazy import lazy_names
from plcbuilder.project.model import Procedure, Project, ProjectError, Settings, parse_settings

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)

if TYPE_CHECKING:
    from plcbuilder.project.build import BuildResult, ProcedureBuild, build_project
    from plcbuilder.project.new import create_project

__all__ = ["BuildResult", "ProcedureBuild", "Procedure", "Project", "ProjectError", "Settings",
           "build_project", "create_project", "parse_settings"]

__getattr__ = lazy_names(__name__, {"BuildResult": "build", "ProcedureBuild": "build",
                                     "build_project": "build", "create_project": "new"})
