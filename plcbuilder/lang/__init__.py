"""The PLC language: preprocessor, parser, checker, code generator.

Its output format, the diagnostics, is re-exported here for the stages that
consume them (project, lsp)."""

from plcbuilder.diagnostics import Diagnostic, Related, Severity, Span, error, render_text

__all__ = ["Diagnostic", "Related", "Severity", "Span", "error", "render_text"]
