"""The project folder model (``model``), Build All (``build``) and ``plcbuilder
new`` (``new``).

Build All's names load on first use (PEP 562): opening a project (``model``)
does not load the compiler.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from plcbuilder.project.model import Procedure, Project, ProjectError, Settings, parse_settings

if TYPE_CHECKING:
    from plcbuilder.project.build import BuildResult, ProcedureBuild, build_project
    from plcbuilder.project.new import create_project

__all__ = ["BuildResult", "ProcedureBuild", "Procedure", "Project", "ProjectError", "Settings",
           "build_project", "create_project", "parse_settings"]

_LAZY = {"BuildResult": "plcbuilder.project.build", "ProcedureBuild": "plcbuilder.project.build",
         "build_project": "plcbuilder.project.build", "create_project": "plcbuilder.project.new"}


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
