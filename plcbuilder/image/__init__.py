"""The uploadable image: a ROMFS disk image (``romfs``) holding one compiled
procedure per file and a manifest (``manifest``); the code size limits
(``limits``, light: a project reads them without loading the image code).

The names below load their module when first used (PEP 562), so that
importing ``plcbuilder.image.limits`` costs only that module."""

from plcbuilder._support.lazy import lazy_names

_WHERE = {"Image": "manifest", "ImageProcedure": "manifest", "read_image": "manifest",
          "valid_name": "manifest", "write_image": "manifest", "Limits": "limits",
          "ImageError": "romfs", "read_romfs": "romfs", "write_romfs": "romfs"}


__getattr__ = lazy_names(__name__, _WHERE)


__all__ = sorted(_WHERE)
