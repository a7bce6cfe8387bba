"""Recording a session: everything done to a controller from outside, at its
tick, as a scenario file that replays it (SPEC §7).

The controller records its own public actions (image loads, starts, Stop,
inputs, ADC, host events, input bindings, writes, forces and releases) when
they succeed; what the procedures do by themselves is not recorded, because a
replay with the same image and machine does it again, tick for tick.

    c.recorder.text()          # the scenario file, with a header of comments

An image load is the line ``upload IMAGE @ MS``: ``IMAGE`` is the image's
identity (:func:`image_id`, a CRC-32 over the procedures' names and CRCs);
``plcbuilder run PROJECT --scenario rec.txt`` loads the project's image there
instead of at 0, and says so when the project's image is not the one recorded.
"""

from __future__ import annotations

import zlib

from plcbuilder._support.records import replace
from plcbuilder.controller.scenario import Action

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Callable, Iterable, Optional

#: Actions recorded at most (a week of clicking); the oldest go first, and the text says so.
MAX_ACTIONS = 1_000_000


def image_id(programs: Iterable) -> str:
    """An image's identity: CRC-32 (hex) over its procedures' names and code CRCs."""
    rows = sorted(f"{p.name}:{p.crc32:08x}" for p in programs)
    return f"{zlib.crc32(';'.join(rows).encode('utf-8')):08x}"


class Recorder:
    """The actions of one controller's session, oldest first."""

    def __init__(self):
        self.actions: list[Action] = []
        self.dropped = 0
        self.on = True
        #: where in a tick an action is done (``Action.at``): the controller's
        #: halt point while it is halted mid-tick, else None
        self.where: Optional[Callable[[], Optional[tuple]]] = None

    def add(self, action: Action) -> None:
        if not self.on:
            return
        at = self.where() if self.where is not None else None
        if at is not None:
            action = replace(action, at=at)
        self.actions.append(action)
        if len(self.actions) > MAX_ACTIONS:
            cut = len(self.actions) - MAX_ACTIONS
            del self.actions[:cut]
            self.dropped += cut

    def clear(self) -> None:
        self.actions.clear()
        self.dropped = 0

    def uploads(self) -> list[Action]:
        return [a for a in self.actions if a.kind == "upload"]

    def text(self, t_end: int, header: Iterable[str] = ()) -> str:
        """The scenario file: comment lines (``header``, the span), then one line
        per action in the order they were done."""
        lines = ["# PLC Builder session recording (a scenario file: docs/traces.md)"]
        lines += [f"# {h}" for h in header]
        lines.append(f"# recorded to t = {t_end} ms: replay with  plcbuilder run PROJECT "
                     f"--scenario FILE --ms {t_end}")
        if self.dropped:
            lines.append(f"# the first {self.dropped} actions were dropped (more than "
                         f"{MAX_ACTIONS}): this recording does not replay the whole session")
        lines += [a.describe() for a in self.actions]
        return "\n".join(lines) + "\n"
