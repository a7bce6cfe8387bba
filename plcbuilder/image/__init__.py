"""The uploadable image: a ROMFS disk image (``romfs``) holding one compiled
procedure per file and a manifest (``manifest``); the code size limits
(``limits``, light: a project reads them without loading the image code).

The names below load their module when first used (PEP 562), so that
importing ``plcbuilder.image.limits`` costs only that module."""

import importlib

_WHERE = {"Image": "manifest", "ImageProcedure": "manifest", "read_image": "manifest",
          "valid_name": "manifest", "write_image": "manifest", "Limits": "limits",
          "ImageError": "romfs", "read_romfs": "romfs", "write_romfs": "romfs"}


def __getattr__(name: str):
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


__all__ = sorted(_WHERE)
