"""The project folder model (``model``), Build All (``build``) and ``plcbuilder
new`` (``new``)."""

from plcbuilder.project.build import BuildResult, ProcedureBuild, build_project
from plcbuilder.project.model import Procedure, Project, ProjectError, Settings, parse_settings
from plcbuilder.project.new import create_project

__all__ = ["BuildResult", "ProcedureBuild", "Procedure", "Project", "ProjectError", "Settings",
           "build_project", "create_project", "parse_settings"]
