"""A folder of the package's data (``resources/...``), found quickly.

When the package is files on disk (it nearly always is) the folder is a
:class:`~pathlib.Path` beside this code; only a package that is not (a zip)
goes through :mod:`importlib.resources`, which takes a millisecond or more to
import on the IDE's way to its first paint.
"""

from __future__ import annotations

from pathlib import Path

#: the package's own folder (``plcbuilder/``)
_PACKAGE = Path(__file__).resolve().parent.parent


def data_folder(*parts: str):
    """The package's folder ``parts`` (say ``"resources", "icons"``): a Path on
    disk, else importlib.resources' Traversable (both have ``joinpath``,
    ``iterdir``, ``is_file``, ``read_bytes``)."""
    folder = _PACKAGE.joinpath(*parts)
    if folder.is_dir():
        return folder
    from importlib import resources
    return resources.files(_PACKAGE.name).joinpath(*parts)
