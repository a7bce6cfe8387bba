"""The IDE's icons: small SVGs in ``plcbuilder/resources/icons`` (package data),
loaded once each. An unknown name gives an empty icon, never an error."""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

from PySide6.QtGui import QIcon

if TYPE_CHECKING:
    from PySide6.QtGui import QPixmap

from plcbuilder._support.package_data import data_folder

ICON_DIR = ("resources", "icons")


def _ref(*parts: str):
    return data_folder(*ICON_DIR).joinpath(*parts)


def icon_names() -> list[str]:
    ref = _ref()
    try:
        return sorted(p.name[:-4] for p in ref.iterdir() if p.name.endswith(".svg"))
    except OSError:
        return []


def icon_path(name: str) -> str:
    """A file path of an icon, for style sheets ('' when the package is not on disk)."""
    ref = _ref(f"{name}.svg")
    try:
        return str(ref).replace("\\", "/") if ref.is_file() else ""
    except (OSError, TypeError):
        return ""


@lru_cache(maxsize=None)
def svg_data(name: str) -> bytes:
    ref = _ref(f"{name}.svg")
    try:
        return ref.read_bytes()
    except (OSError, FileNotFoundError):
        return b""


@lru_cache(maxsize=None)
def icon(name: str) -> QIcon:
    """The icon called name (an SVG rendered crisply at every size asked for).

    From a file, Qt's SVG icon engine renders a size when it is first shown
    (rendering six sizes of every icon up front took a tenth of the IDE's
    start-up); without the file (a zipped package), the sizes are rendered
    here."""
    path = icon_path(name)
    if path:
        ic = QIcon(path)
        if not ic.isNull():
            return ic
    data = svg_data(name)
    if not data:
        return QIcon()
    ic = QIcon()
    for size in (16, 20, 24, 32, 48, 64):
        ic.addPixmap(_render(data, size))
    return ic


def pixmap(name: str, size: int = 16) -> QPixmap:
    from PySide6.QtGui import QPixmap
    data = svg_data(name)
    return _render(data, size) if data else QPixmap()


def _render(data: bytes, size: int) -> QPixmap:
    # these here, not at import: a Qt class first used from Python makes its
    # enum classes (the Qt namespace's 93 take 35 ms), which the window's
    # first frame does without
    from PySide6.QtCore import QByteArray, QRectF, Qt
    from PySide6.QtGui import QImage, QPainter, QPixmap
    from PySide6.QtSvg import QSvgRenderer
    renderer = QSvgRenderer(QByteArray(data))
    img = QImage(size, size, QImage.Format.Format_ARGB32_Premultiplied)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    renderer.render(p, QRectF(0, 0, size, size))
    p.end()
    return QPixmap.fromImage(img)
