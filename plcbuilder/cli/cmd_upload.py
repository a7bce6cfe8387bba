"""``plcbuilder upload IMAGE``: send an eeprom.rom image to the running controller.

The controller accepts an image only whole and valid (ROMFS structure,
manifest, every CRC, the size limits); otherwise it refuses it with the reason,
which is printed, exit status 1, and the previous image keeps running.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from plcbuilder.cli._link_opts import (EXIT_FAIL, add_link_options, add_project_option,
                                       image_target, run_client)


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "upload", help="upload an eeprom.rom image to the running controller",
        description="Upload IMAGE (build/eeprom.rom) to the controller. A refused image "
                    "prints the controller's reason and exits 1; the previous image keeps "
                    "running.")
    p.add_argument("image", type=Path, metavar="IMAGE", help="the image (build/eeprom.rom)")
    add_project_option(p)
    add_link_options(p)
    return p


def run(args: argparse.Namespace) -> int:
    import sys

    from plcbuilder._support.files import read_bounded
    from plcbuilder.link.protocol import MAX_IMAGE
    try:
        data = read_bounded(args.image, MAX_IMAGE, "controller image")
    except OSError as exc:
        print(f"plcbuilder upload: cannot read {args.image}: {exc.strerror or exc}",
              file=sys.stderr)
        return EXIT_FAIL

    from plcbuilder.api import ProjectError
    try:
        target, target_name = image_target(args.image, args.project)
    except ProjectError as exc:
        print(f"plcbuilder upload: {exc}", file=sys.stderr)
        return EXIT_FAIL

    def body(client, out) -> int:
        r = client.upload(data, target=target)
        procs = r.get("procedures", [])
        hw = [p for p in procs if p.get("kind") == "hardware"]
        on = f", target {target_name}" if target is not None else ""
        out.print(f"uploaded {args.image}: {len(procs)} procedures ({len(hw)} hardware, "
                  f"{len(procs) - len(hw)} software), hardware code {r.get('hw_total', 0)} bytes, "
                  f"image CRC-32 {r.get('image_crc32')}{on}")
        return 0

    return run_client(args, body, "upload")
