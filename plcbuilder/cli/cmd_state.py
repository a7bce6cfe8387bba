"""``plcbuilder state [--json]``: what the running controller is doing.

``--json`` prints the whole state as one JSON object: at least ``image`` (the
loaded procedures with sizes and CRCs), ``running`` (the hardware procedure
running, or null), ``software`` (the software procedures running) and ``t_ms``;
also ``proc``, ``inputs``, ``outputs`` (pins on), ``pwm``, ``dac``, ``adc``,
``axes``, ``speed`` and ``server``.
"""

from __future__ import annotations

import argparse
import json

from plcbuilder.cli._link_opts import add_link_options, run_client


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "state", help="show the running controller's state",
        description="Show what the controller runs, its outputs and its image. --json prints "
                    "one JSON object (image, running, software, t_ms, ...).")
    p.add_argument("--json", action="store_true", help="print the state as JSON")
    add_link_options(p)
    return p


def _pins(pins) -> str:
    return ", ".join(str(p) for p in pins) if pins else "none"


def render(st, out) -> None:
    """A ControllerStatus as lines of text."""
    speed = st.speed
    mode = speed.get("mode", "?")
    if mode == "factor":
        mode = f"{speed.get('factor'):g}x"
    out.print(f"{out.paint('heading', 't')} = {st.t_ms} ms ({mode})")
    proc_name = st.proc_name
    out.print(f"running: {st.running or 'nothing'}"
              f" (proc {st.proc}{' ' + proc_name if proc_name else ''})")
    out.print(f"software: {', '.join(st.software) or 'none'}")
    out.print(f"inputs on: {_pins(st.inputs)}")
    out.print(f"outputs on: {_pins(st.outputs)}")
    if st.axes:
        out.print("axes: " + "  ".join(f"{k} {v / 100:.2f}" for k, v in st.axes.items()))
    crc = st.image_crc32
    out.print(f"image: {len(st.image)} procedures" + (f" (CRC-32 {crc})" if crc else ""))
    for p in st.image:
        out.print(f"  {p.get('name'):<24} {p.get('kind'):<9} {p.get('size'):>6} bytes  "
                  f"crc {p.get('crc32')}")
    err = st.server.get("error")
    if err:
        out.print(out.paint("bad", f"simulation error: {err}"))


def run(args: argparse.Namespace) -> int:
    def body(client, out) -> int:
        st = client.state()
        if args.json:
            out.print(json.dumps(st.to_dict(), indent=2, sort_keys=True))
        else:
            render(st, out)
        return 0

    return run_client(args, body, "state")
