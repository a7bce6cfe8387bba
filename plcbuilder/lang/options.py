"""How a procedure is compiled (:class:`CompileOptions`), and by which
compiler (:data:`COMPILER_VERSION`).

Its own module, without the compiler's stages: a project (which says how its
files are compiled) and the IDE's first paint do not load lark. The pipeline
(:mod:`plcbuilder.lang.pipeline`) imports it from here, and so does the facade.
"""

from __future__ import annotations

from pathlib import Path

from plcbuilder._support.records import dataclass
from plcbuilder.bytecode.kind import Kind

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

__all__ = ["COMPILER_VERSION", "CompileOptions"]

#: the compiler's own version (part of the build cache's compiler fingerprint)
COMPILER_VERSION = "1"


@dataclass(frozen=True)
class CompileOptions:
    kind: Kind = Kind.HARDWARE
    strict: bool = False
    include_dirs: tuple = ()
    code_limit: Optional[int] = None   # None: the kind's default (512 / 16384)
    #: the folder headers must stay inside (a project's); None: the procedure's
    #: own folder. Include folders named outside it are allowed too.
    root: Optional[Path] = None
    #: the controller the procedure is for (bytecode.targets.TARGETS; docs/targets.md)
    target: str = "mycnc"

    @property
    def limit(self) -> int:
        return self.code_limit if self.code_limit is not None else self.kind.code_limit
