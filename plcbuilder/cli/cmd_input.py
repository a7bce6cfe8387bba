"""``plcbuilder input PIN=0|1 …``: set inputs of the running controller by hand.

An input set by hand overrides the machine's own wiring of that pin from then
on. ``--adc CH=VALUE`` sets an ADC channel the same way.
"""

from __future__ import annotations

import argparse

from plcbuilder._support.numbers import INT32, parse_int_in
from plcbuilder.cli._link_opts import EXIT_USAGE, add_link_options, run_client

PIN_RANGE = (0, 255)          # the most inputs a machine has
CHANNEL_RANGE = (0, 7)


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "input", help="set inputs (and ADC channels) of the running controller",
        description="Set each input PIN to 0 or 1 (it then overrides the machine's wiring of "
                    "that pin). --adc CH=VALUE sets ADC channel CH.")
    p.add_argument("inputs", nargs="*", metavar="PIN=0|1", help="an input and its value")
    p.add_argument("--adc", action="append", default=[], metavar="CH=VALUE",
                   help="set ADC channel CH to VALUE (repeatable)")
    add_link_options(p)
    return p


def _pairs(items: list[str], shape: str, what: str, keys: tuple[int, int],
           values: tuple[int, int]):
    """``KEY=VALUE`` pairs, each number in its range (ValueError naming the range)."""
    out = []
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"expected {shape}, got {item!r}")
        k = parse_int_in(key, *keys, f"{shape}: {what}")
        v = parse_int_in(value, *values, f"{shape}: the value of {what} {k}")
        out.append((k, v))
    return out


def run(args: argparse.Namespace) -> int:
    import sys
    try:
        pins = _pairs(args.inputs, "PIN=0|1", "input pin", PIN_RANGE, (0, 1))
        adcs = _pairs(args.adc, "--adc CH=VALUE", "ADC channel", CHANNEL_RANGE, INT32)
    except ValueError as exc:
        print(f"plcbuilder input: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if not pins and not adcs:
        print("plcbuilder input: give at least one PIN=0|1 or --adc CH=VALUE", file=sys.stderr)
        return EXIT_USAGE

    def body(client, out) -> int:
        for pin, value in pins:
            r = client.set_input(pin, value)
            out.print(f"input {pin} = {value} at t = {r.get('t_ms')} ms")
        for ch, value in adcs:
            r = client.set_adc(ch, value)
            out.print(f"ADC{ch} = {value} at t = {r.get('t_ms')} ms")
        return 0

    return run_client(args, body, "input")
