"""JSON as the project's files and frames allow it."""

from __future__ import annotations

import json


def _reject_constant(name: str):
    raise ValueError(f"{name} is not allowed")


def no_duplicate_keys(pairs):
    """``object_pairs_hook`` refusing a key that appears twice (ValueError)."""
    out = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"key {k!r} appears twice")
        out[k] = v
    return out


def strict_json_loads(text: str):
    """JSON that refuses repeated keys and NaN/Infinity (raises ValueError, or
    RecursionError when nested too deeply)."""
    return json.loads(text, object_pairs_hook=no_duplicate_keys, parse_constant=_reject_constant)
