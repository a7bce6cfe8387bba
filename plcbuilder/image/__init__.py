"""The uploadable image: a ROMFS disk image (``romfs``) holding one compiled
procedure per file and a manifest (``manifest``)."""

from plcbuilder.image.manifest import (Image, ImageProcedure, Limits, read_image, valid_name,
                                       write_image)
from plcbuilder.image.romfs import ImageError, read_romfs, write_romfs

__all__ = ["Image", "ImageError", "ImageProcedure", "Limits", "read_image", "read_romfs",
           "valid_name", "write_image", "write_romfs"]
