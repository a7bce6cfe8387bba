"""Build All: compile every procedure of a project, write build/ and the image.

    compile_all(project) -> [ProcedureBuild]     compile, write nothing (also ``run``'s)
    build_project(project, progress) -> BuildResult

One job a module:

    steps     Build All's steps, in order: problems, cache, compile, build/, the image
    results   ProcedureBuild and BuildResult, their diagnostics packed until asked for
    cache     build/.cache.json, the incremental build cache (its format is described there)
    pool      compiling here or in worker processes, one per core
    problems  a procedure's name, target or link out of the project; build/ out of it

Diagnostics cross processes and the cache as :meth:`Diagnostic.to_dict` rows
(plcbuilder.diagnostics holds that serialisation).
"""

from plcbuilder.project.build.cache import (CACHE_FILE, CACHE_VERSION, MAX_CACHE_BYTES, RACY_NS,
                                            compiler_fingerprint)
from plcbuilder.project.build.pool import MAX_WORKERS, PARALLEL_MIN
from plcbuilder.project.build.results import BIN_SUFFIX, BuildResult, ProcedureBuild
from plcbuilder.project.build.steps import LOCK_FILE, Progress, build_project, compile_all

__all__ = ["BIN_SUFFIX", "CACHE_FILE", "CACHE_VERSION", "LOCK_FILE", "MAX_CACHE_BYTES",
           "MAX_WORKERS", "PARALLEL_MIN", "RACY_NS", "BuildResult", "ProcedureBuild", "Progress",
           "build_project", "compile_all", "compiler_fingerprint"]
