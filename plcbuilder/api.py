"""The facade: plain functions that compose the pipeline.

    compile_source / compile_file   source -> diagnostics + Program
    load_program / disassemble      binary -> Program -> listing
    run (plcbuilder.simulate)       procedures -> a simulated controller run
    build_project                   a project folder -> build/*.bin + build/eeprom.rom

Options are passed in; nothing here keeps global state.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Optional

from plcbuilder.bytecode import disasm
from plcbuilder.bytecode.abi import proc_name
from plcbuilder.bytecode.program import Kind, LoadError, Program
from plcbuilder.lang.compiler import (CompileOptions, CompileResult, compile_bytes, compile_file,
                                      compile_source)
from plcbuilder.lang.preprocess import BUILTIN_PREFIX, builtin_header, builtin_header_names
from plcbuilder._support.files import atomic_write
from plcbuilder.project import BuildResult, Project, ProjectError, build_project, create_project

__all__ = ["atomic_write", "proc_name", "BUILTIN_PREFIX", "builtin_header", "builtin_header_names", "BuildResult", "CompileOptions", "CompileResult", "Kind", "LoadError", "Program",
           "Project", "ProjectError", "build_project", "compile_bytes", "compile_file",
           "compile_source", "create_project", "disassemble", "kind_for_path", "load_program"]


def load_program(path) -> Program:
    """Read a compiled procedure (.bin); raises LoadError saying why it is refused."""
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise LoadError(f"cannot read {path}: {exc.strerror or exc}") from None
    return Program.from_bytes(data)


def disassemble(program: Program, source_line: Optional[Callable[[str, int], Optional[str]]] = None) -> str:
    return disasm.render_text(program, source_line)


def kind_for_path(path, software: bool = False) -> Kind:
    """A procedure in a folder named ``software`` is a software procedure."""
    if software or Path(path).parent.name == "software":
        return Kind.SOFTWARE
    return Kind.HARDWARE
