#!/usr/bin/env python3
"""Brings the standard schemas the suite checks our files against, from the
packages that ship them (fetched data is never committed to this repository):

    junit-10.xsd   the Jenkins xUnit plugin's JUnit schema, from pytest's source
                   distribution on PyPI (testing/example_scripts/junit-10.xsd),
                   of the pytest version the test extras pin

into ``.venv/share/plcbuilder-tests/`` (``scripts/_venv.sh`` runs this once
after installing the test extras). A schema that cannot be had leaves a note;
the tests that need it skip and say so.

    .venv/bin/python scripts/test_schemas.py
"""

from __future__ import annotations

import subprocess
import sys
import tarfile
import tempfile
from importlib import metadata
from pathlib import Path

DEST = Path(sys.prefix) / "share" / "plcbuilder-tests"
#: name -> (the PyPI project whose sdist ships it, its path inside the sdist)
SCHEMAS = {"junit-10.xsd": ("pytest", "testing/example_scripts/junit-10.xsd")}


def fetch(name: str) -> Path:
    project, member = SCHEMAS[name]
    version = metadata.version(project)
    with tempfile.TemporaryDirectory(prefix="plcb-schemas-") as tmp:
        subprocess.run([sys.executable, "-m", "pip", "download", "-q", "--no-deps",
                        "--no-binary", ":all:", f"{project}=={version}", "-d", tmp],
                       check=True, timeout=600, stdin=subprocess.DEVNULL)
        sdist = next(Path(tmp).glob(f"{project}-*.tar.gz"))
        with tarfile.open(sdist) as tar:
            f = tar.extractfile(f"{project}-{version}/{member}")
            if f is None:
                raise FileNotFoundError(f"{member} in {sdist.name}")
            data = f.read()
    DEST.mkdir(parents=True, exist_ok=True)
    out = DEST / name
    tmp_out = out.with_suffix(".tmp")
    tmp_out.write_bytes(data)
    tmp_out.replace(out)
    return out


def main() -> int:
    bad = 0
    for name in SCHEMAS:
        if (DEST / name).is_file():
            continue
        try:
            print(f"test schemas: {fetch(name)} (from {SCHEMAS[name][0]}'s source distribution)")
        except (OSError, subprocess.SubprocessError, StopIteration, KeyError,
                tarfile.TarError, metadata.PackageNotFoundError) as exc:
            print(f"note: {name} could not be had ({exc}); the tests that check against it "
                  f"will skip", file=sys.stderr)
            bad += 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
