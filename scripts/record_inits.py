"""Write ``plcbuilder/_support/record_inits.py``: the ``__init__`` template of
each shape of fields the package's record classes have (see
``plcbuilder/_support/records.py``), so that a command loads them from the
bytecode cache instead of compiling them at every start (issue 26.1).
Run it after adding or changing a record class; tests/_support/test_records.py
says when it is due.

    .venv/bin/python scripts/record_inits.py
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET = ROOT / "plcbuilder" / "_support" / "record_inits.py"


def package_shapes() -> set:
    """The shapes of the record classes of every module of the package but the
    IDE's (the IDE makes its own when it starts; its package is not imported)."""
    import plcbuilder
    from plcbuilder._support import records
    for name in _modules(plcbuilder.__path__, "plcbuilder."):
        importlib.import_module(name)
    return records.made_shapes()


def _modules(path, prefix: str):
    for m in pkgutil.iter_modules(path, prefix):
        if m.name == "plcbuilder.ide" or m.name.endswith(".__main__"):
            continue
        yield m.name
        if m.ispkg:
            yield from _modules(importlib.import_module(m.name).__path__, m.name + ".")


def source() -> str:
    from plcbuilder._support import records
    return records.inits_source(package_shapes())


def main() -> int:
    sys.path.insert(0, str(ROOT))
    TARGET.write_text(source(), encoding="utf-8")
    print(f"wrote {TARGET.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
