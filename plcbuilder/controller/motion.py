"""The simulated motion controller: PLC moves (g0moveA) and jogs, 1 ms at a time.

Units inside: positions in 0.01 mm (0.01° on rotary axes) as floats, time in ms,
velocity in 0.01 mm per ms, acceleration in 0.01 mm per ms². Reported positions
are the floats rounded to the nearest integer.

Decisions (documented for users in docs/machine.md, "Motion"):

- A g0moveA of several axes is one coordinated straight line: every axis starts
  and arrives together. The path speed and acceleration are the largest that
  keep every axis within its own rapid speed and acceleration. The profile is a
  trapezoid (a triangle when the move is too short to reach full speed).
- A move starts ``start_latency_ms`` after the call (default 2). A move called
  while another runs (or while a jog runs) waits for it to end. Incremental
  targets are taken from where the axis is when the move starts.
- Every move keeps the motion controller busy for at least 1 ms, even when it
  goes nowhere, so a PLC waiting for 6060 to become 0 always sees it.
- A stop (LINE_STOP and friends) decelerates the move at its acceleration, and
  brings jogs to rest at their jog acceleration; moves still waiting to start
  are dropped.
- Soft limits clip a move where its line leaves the soft box (the move
  decelerates to stop exactly there) and end a jog at the limit; a note says so.
- Jogs: each axis is independent, with its own speed and acceleration.
"""

from __future__ import annotations

import math
from collections import deque

from plcbuilder.bytecode.abi import AXES, MOTION_CODE_IDLE

from .machine_config import MachineConfig

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

N_AXES = len(AXES)
JOG_AXES = 8              # 8635 and 100020.. reach X..V
DEFAULT_JOG_UNITS = 1000  # 8632 unset: a jog speed value is mm/min


def mm_per_min_to_internal(v: float) -> float:
    """mm/min -> 0.01 mm per ms."""
    return v / 600.0


def mm_per_s2_to_internal(a: float) -> float:
    """mm/s² -> 0.01 mm per ms²."""
    return a / 10000.0


def fmt_mm(units: float) -> str:
    """0.01 mm units as 'N.NN'."""
    return f"{round(units) / 100:.2f}"


#: The least speed (0.01 mm/ms) and acceleration (0.01 mm/ms²) the profiles use:
#: the machine description's bounds keep real values far above it, and a
#: value at or below it (or NaN) can never become a division by zero.
_TINY = 1e-12


def _floor(x: float) -> float:
    return x if x > _TINY else _TINY


class Profile:
    """A 1-D motion profile s(t), piecewise constant acceleration.

    ``phases`` holds (t0, s0, v0, a) with t relative to the move's start; the
    profile ends at ``t_end`` with s = ``s_end`` and v = 0.
    """

    __slots__ = ("phases", "t_end", "s_end")

    def __init__(self, phases: list[tuple[float, float, float, float]], t_end: float,
                 s_end: float):
        self.phases = phases
        self.t_end = t_end
        self.s_end = s_end

    @classmethod
    def trapezoid(cls, dist: float, vmax: float, acc: float) -> "Profile":
        if not dist > 0:
            return cls([(0.0, 0.0, 0.0, 0.0)], 1.0, 0.0)
        vmax, acc = _floor(vmax), _floor(acc)
        t_acc = vmax / acc
        d_acc = 0.5 * vmax * t_acc
        if 2 * d_acc >= dist:
            vpeak = math.sqrt(acc * dist)
            t_acc = vpeak / acc
            phases = [(0.0, 0.0, 0.0, acc), (t_acc, dist / 2, vpeak, -acc)]
            return cls(phases, 2 * t_acc, dist)
        t_cruise = (dist - 2 * d_acc) / vmax
        t2 = t_acc + t_cruise
        phases = [(0.0, 0.0, 0.0, acc), (t_acc, d_acc, vmax, 0.0), (t2, dist - d_acc, vmax, -acc)]
        return cls(phases, t2 + t_acc, dist)

    def at(self, t: float) -> tuple[float, float]:
        """(s, v) at time t."""
        if t >= self.t_end:
            return self.s_end, 0.0
        for t0, s0, v0, a in reversed(self.phases):
            if t >= t0:
                dt = t - t0
                return s0 + v0 * dt + 0.5 * a * dt * dt, v0 + a * dt
        return 0.0, 0.0

    def stop_from(self, t: float, acc: float) -> "Profile":
        """The profile that decelerates at ``acc`` from its state at t (itself when
        it already stops sooner)."""
        s, v = self.at(t)
        if v <= 0:
            return Profile([(t, s, 0.0, 0.0)], t, s)
        acc = _floor(acc)
        s_stop = s + v * v / (2 * acc)
        if s_stop >= self.s_end - 1e-9:
            return self
        return Profile([(t, s, v, -acc)], t + v / acc, s_stop)


class Move:
    """One coordinated straight-line move in progress."""

    __slots__ = ("axes", "start", "unit", "profile", "t", "accel", "clip_note", "final", "code",
                 "homing", "stopped")

    def __init__(self, axes, start, unit, profile, accel, clip_note, final, code=0, homing=()):
        self.axes = axes            # axis indexes that take part
        self.start = start          # {axis: start position}
        self.unit = unit            # {axis: component of the unit direction}
        self.profile = profile
        self.t = 0                  # ms since the move started
        self.accel = accel          # path acceleration (for a stop)
        self.clip_note = clip_note  # note to give when it ends at a soft limit, or None
        self.final = final          # {axis: exact end position} when it runs to the end
        self.code = code            # what 6060 reads while it runs: 0 (G0, a PLC move) or 1 (G1)
        self.homing = homing        # the axes this move homes (a G-code job's G28)
        self.stopped = False        # a stop message cut it short


class Motion:
    """Positions, velocities, the move in progress, the move queue and jogs."""

    def __init__(self, config: MachineConfig, notes: list):
        self.notes = notes                      # shared (level, text) list of the machine
        self.latency = config.start_latency_ms
        self.watchdog_ms = config.jog_watchdog_ms
        self.present = [a in config.axes for a in AXES]
        self.present_idx = [i for i, a in enumerate(AXES) if a in config.axes]
        self.vmax = [0.0] * N_AXES
        self.amax = [0.0] * N_AXES
        self.soft_min: list[Optional[float]] = [None] * N_AXES
        self.soft_max: list[Optional[float]] = [None] * N_AXES
        self.start_pos = [0.0] * N_AXES
        self.offset = [0] * N_AXES
        self.jog_default = [0] * N_AXES
        self.unit = ["mm"] * N_AXES
        for name, ax in config.axes.items():
            i = AXES.index(name)
            self.vmax[i] = mm_per_min_to_internal(ax.rapid)
            self.amax[i] = mm_per_s2_to_internal(ax.accel)
            self.soft_min[i] = None if ax.soft_min is None else float(round(ax.soft_min * 100))
            self.soft_max[i] = None if ax.soft_max is None else float(round(ax.soft_max * 100))
            self.start_pos[i] = float(round(ax.start * 100))
            self.offset[i] = round(ax.offset * 100)
            self.jog_default[i] = round(ax.jog)
            self.unit[i] = "deg" if ax.rotary else "mm"
        self.soft_limits = True
        self.reset()

    # ------------------------------------------------------------ state
    def reset(self) -> None:
        self.pos = list(self.start_pos)
        self.ipos = [round(p) for p in self.pos]
        self.vel = [0.0] * N_AXES
        self._vel_seen: Optional[list] = None     # the velocities velocity_report last saw
        self._vel_report: tuple = ()
        self.move: Optional[Move] = None
        self.queue: deque = deque()             # (due_t, flags, mask, distance, recorded)
        self.recorded: dict[int, tuple[int, int]] = {}   # delayed-start targets
        self.jog_speed = list(self.jog_default)  # 8634 speed values per axis
        self.jog_time_ms = 0                      # 8631 (0: use the axes' accelerations)
        self.jog_units = 0                        # 8632 (0: 1000)
        self.hw_dir = 0                           # 8635 as applied
        self.hw_last_write: Optional[int] = None  # tick of the last 8635 write
        self.jog_cmds: deque = deque()            # (due_t, dir)
        self.soft_speed = [0] * N_AXES            # software PLC jog speed values
        self.jog_target = [0.0] * N_AXES
        self.jog_acc = [0.0] * N_AXES
        self.jogging = False
        self.soft_limits = True
        self._warned: set = set()
        #: which axes have been homed since power-on (G28 of a G-code job)
        self.homed = [False] * N_AXES
        #: axis -> the desired position a TG Motion PLC wrote (TGM_Servo): the
        #: axis follows it at up to its rapid speed while no move or jog runs
        self.follow: dict[int, float] = {}

    @property
    def busy(self) -> bool:
        """A move or a jog is running (6060 reads 0, or 1 for a job's G1)."""
        return self.move is not None or self.jogging

    @property
    def motion_code(self) -> int:
        """What 6060 reads: the code of the move running (0 for a G0 or PLC move
        or a jog, 1 for a G-code job's G1), 0x4d when idle."""
        m = self.move
        if m is not None:
            return m.code
        return 0 if self.jogging else MOTION_CODE_IDLE

    @property
    def idle(self) -> bool:
        """Nothing moves and nothing waits to move (a G-code job's next move may start)."""
        return self.move is None and not self.jogging and not self.queue and not self.jog_cmds \
            and not any(self.vel)

    @property
    def needs_advance(self) -> bool:
        return (self.move is not None or self.jogging or bool(self.queue)
                or bool(self.jog_cmds) or self.hw_dir != 0 or bool(self.follow))

    def servo_target(self, i: int, position: int) -> None:
        """A desired position (0.01 mm, machine coordinates) for axis i, as a
        TG Motion PLC writes it to a servo every cycle: the axis goes there at
        up to its rapid speed (the drive follows; no profile of its own)."""
        if self.present[i]:
            self.follow[i] = float(position)

    def _step_follow(self) -> bool:
        moved = False
        for i, target in list(self.follow.items()):
            d = target - self.pos[i]
            step = max(-self.vmax[i], min(self.vmax[i], d))
            self.pos[i] += step
            self.vel[i] = step
            self.ipos[i] = round(self.pos[i])
            moved = moved or step != 0.0
            if abs(target - self.pos[i]) < 1e-9:
                self.pos[i] = target
                self.vel[i] = 0.0
                del self.follow[i]
        return moved

    def note(self, level: str, text: str) -> None:
        self.notes.append((level, text))

    def warn_once(self, key, text: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            self.note("warning", text)

    # ------------------------------------------------------------ moves
    def g0move(self, t: int, flags: int, mask: int, distance: int) -> None:
        """g0moveA(flags, mask, distance) called in tick t."""
        mask &= (1 << N_AXES) - 1
        if flags & 0x80:
            for i in range(N_AXES):
                if mask >> i & 1:
                    self.recorded[i] = (flags, distance)
            return
        recorded, self.recorded = self.recorded, {}
        self.queue.append((t + self.latency, flags, mask, distance, recorded))
        if self.latency == 0:
            self._start_due(t)

    def _start_due(self, t: int) -> None:
        while self.queue and self.move is None and not self.jogging and self.queue[0][0] <= t:
            _, flags, mask, distance, recorded = self.queue.popleft()
            self._start_move(flags, mask, distance, recorded)

    def line_to(self, target: dict[int, float], feed: Optional[float] = None, code: int = 0,
                homing: tuple = ()) -> None:
        """A G-code job's move, starting now: each axis of ``target`` (machine
        position, 0.01 mm) in one straight line, at the rapid speed (G0) or at
        ``feed`` mm/min along the path (G1); ``homing``: the axes it homes."""
        axes = [i for i in target if self.present[i]]
        self._begin(axes, {i: self.pos[i] for i in axes}, {i: float(target[i]) for i in axes},
                    None if feed is None else mm_per_min_to_internal(feed), code, homing)

    def line_ms(self, start: dict[int, float], target: dict[int, float],
                feed: Optional[float] = None) -> float:
        """How long :meth:`line_to` would take from ``start`` to ``target`` (0.01 mm,
        by axis index) at the rapid speeds or ``feed`` mm/min, accelerating as a
        move does (soft limits aside): a G-code job's time left."""
        delta = {i: target[i] - start[i] for i in target if self.present[i]}
        dist = math.sqrt(sum(d * d for d in delta.values()))
        unit = {i: d / dist for i, d in delta.items() if d} if dist >= 1e-9 else {}
        if not unit:
            return 1.0
        vmax = min(self.vmax[i] / abs(u) for i, u in unit.items())
        if feed is not None:
            vmax = min(vmax, mm_per_min_to_internal(feed))
        acc = min(self.amax[i] / abs(u) for i, u in unit.items())
        return Profile.trapezoid(dist, vmax, acc).t_end

    def _start_move(self, flags: int, mask: int, distance: int, recorded: dict) -> None:
        axes, start, target = [], {}, {}
        for i in range(N_AXES):
            if not mask >> i & 1:
                continue
            if not self.present[i]:
                self.warn_once(("move", i), f"g0moveA: the machine has no {AXES[i]} axis; "
                                            f"that part of the move is ignored")
                continue
            f, d = recorded.get(i, (flags, distance))
            if f & 1:
                tgt = d if f & 2 else d + self.offset[i]
            else:
                tgt = self.ipos[i] + d
            axes.append(i)
            start[i] = self.pos[i]
            target[i] = float(tgt)
        self._begin(axes, start, target)

    def _begin(self, axes: list, start: dict, target: dict, vcap: Optional[float] = None,
               code: int = 0, homing: tuple = ()) -> None:
        """Start one straight line from ``start`` to ``target`` (no faster than
        ``vcap`` along the path, 0.01 mm/ms, when given)."""
        for i in axes:
            self.follow.pop(i, None)
        delta = {i: target[i] - start[i] for i in axes}
        dist = math.sqrt(sum(d * d for d in delta.values()))
        if dist < 1e-9:
            # goes nowhere: busy for 1 ms all the same
            self.move = Move([], {}, {}, Profile.trapezoid(0.0, 1.0, 1.0), 1.0, None, {}, code,
                             homing)
            return
        unit = {i: u for i in axes if (u := delta[i] / dist) != 0.0}
        if not unit:                    # too small a step to have a direction
            self.move = Move([], {}, {}, Profile.trapezoid(0.0, 1.0, 1.0), 1.0, None, {}, code,
                             homing)
            return
        vmax = min(self.vmax[i] / abs(u) for i, u in unit.items())
        if vcap is not None:
            vmax = min(vmax, vcap)
        acc = min(self.amax[i] / abs(u) for i, u in unit.items())
        length, clip_note = dist, None
        if self.soft_limits:
            for i, u in unit.items():
                p = start[i]
                if u > 0 and self.soft_max[i] is not None:
                    room = max(0.0, (self.soft_max[i] - p) / u)
                    bound, which = self.soft_max[i], "max"
                elif u < 0 and self.soft_min[i] is not None:
                    room = max(0.0, (self.soft_min[i] - p) / u)
                    bound, which = self.soft_min[i], "min"
                else:
                    continue
                if room < length - 1e-9:
                    length = room
                    stop_at = p + u * room if room > 0 else p
                    clip_note = (f"soft limit: move stopped at {AXES[i]} {fmt_mm(stop_at)} "
                                 f"{self.unit[i]} ({which} {fmt_mm(bound)}); target was "
                                 f"{AXES[i]} {fmt_mm(target[i])}")
        final = {} if clip_note else dict(target)
        self.move = Move(axes, start, unit, Profile.trapezoid(length, vmax, acc), acc,
                         clip_note, final, code, homing)

    def _step_move(self) -> None:
        m = self.move
        m.t += 1
        prof = m.profile
        pos, vel = self.pos, self.vel
        if m.t >= prof.t_end:
            s = prof.s_end
            for i in m.axes:
                pos[i] = m.final[i] if i in m.final else m.start[i] + m.unit.get(i, 0.0) * s
                vel[i] = 0.0
                self.ipos[i] = round(pos[i])
            self.move = None
            if m.clip_note:
                self.note("warning", m.clip_note)
            elif m.homing and not m.stopped:
                for i in m.homing:
                    self.homed[i] = True
            return
        s, v = prof.at(m.t)
        for i in m.axes:
            u = m.unit.get(i, 0.0)
            pos[i] = m.start[i] + u * s
            vel[i] = u * v
            self.ipos[i] = round(pos[i])

    def stop(self) -> None:
        """A stop message: decelerate the move, bring jogs to rest, drop waiting moves."""
        self.follow.clear()
        self.queue.clear()
        self.recorded.clear()
        self.jog_cmds.clear()
        m = self.move
        if m is not None:
            new = m.profile.stop_from(m.t, m.accel)
            m.stopped = True
            if new is not m.profile:
                m.profile = new
                m.final = {}
                m.clip_note = None
        self.hw_dir = 0
        self.hw_last_write = None
        self.soft_speed = [0] * N_AXES
        if self.jogging:
            for i in self.present_idx:
                self._set_jog_target(i, 0.0)

    def halt(self) -> None:
        """Stop everything at once (a hard limit): no deceleration."""
        self.follow.clear()
        self.queue.clear()
        self.recorded.clear()
        self.jog_cmds.clear()
        self.move = None
        self.hw_dir = 0
        self.hw_last_write = None
        self.soft_speed = [0] * N_AXES
        self.jog_target = [0.0] * N_AXES
        self.vel = [0.0] * N_AXES
        self.jogging = False

    # ------------------------------------------------------------- jogs
    def jog_units_value(self) -> int:
        return self.jog_units if self.jog_units > 0 else DEFAULT_JOG_UNITS

    def speed_value_to_internal(self, i: int, speed: int) -> float:
        """A jog speed value (8634, 100020..) in 0.01 mm/ms, capped at the rapid speed."""
        v = mm_per_min_to_internal(abs(speed) * self.jog_units_value() / 1000.0)
        return min(v, self.vmax[i])

    def set_jog_time(self, ms: int) -> None:
        self.jog_time_ms = ms

    def set_jog_units(self, units: int) -> None:
        self.jog_units = units
        self._retarget_all()

    def set_jog_speed(self, value: int) -> None:
        """8634: (mask << 24) | speed."""
        mask = (value >> 24) & 0xFF
        speed = value & 0xFFFFFF
        for i in range(JOG_AXES):
            if mask >> i & 1:
                self.jog_speed[i] = speed
        if self.hw_dir:
            self._retarget_all()

    def jog_write(self, t: int, value: int) -> None:
        """8635 written in tick t: takes effect after the start latency."""
        self.hw_last_write = t
        value &= 0xFFFF
        if self.jog_cmds and self.jog_cmds[-1][1] == value:
            return
        self.jog_cmds.append((t + self.latency, value))
        if self.latency == 0:
            self._apply_jog_cmds(t)

    def soft_jog(self, axis: int, speed: int) -> None:
        """Software PLC jog of one axis (gvarset(100020 + axis, speed)); runs until 0."""
        if not 0 <= axis < JOG_AXES:
            self.warn_once(("softjog", axis), f"software jog: no axis {axis} (0..{JOG_AXES - 1})")
            return
        if not self.present[axis]:
            if speed:
                self.warn_once(("jog", axis), f"jog: the machine has no {AXES[axis]} axis")
            return
        if speed and self.move is not None:
            self.note("warning", f"software jog of {AXES[axis]} ignored: a g0moveA move is running")
            return
        self.soft_speed[axis] = speed
        self._retarget(axis)

    def _apply_jog_cmds(self, t: int) -> None:
        while self.jog_cmds and self.jog_cmds[0][0] <= t:
            _, value = self.jog_cmds.popleft()
            if value and self.move is not None:
                self.note("warning", "jog ignored: a g0moveA move is running")
                continue
            self.hw_dir = value
            if not value:
                self.hw_last_write = None
            for i in range(JOG_AXES):
                if not self.present[i] and (value >> i & 1 or value >> (8 + i) & 1):
                    self.warn_once(("jog", i), f"jog: the machine has no {AXES[i]} axis")
            self._retarget_all()

    def _hw_velocity(self, i: int) -> Optional[float]:
        """The target velocity 8635 gives axis i, or None when 8635 leaves it alone."""
        plus = self.hw_dir >> i & 1
        minus = self.hw_dir >> (8 + i) & 1
        if not plus and not minus:
            return None
        sign = plus - minus
        return sign * self.speed_value_to_internal(i, self.jog_speed[i])

    def _retarget_all(self) -> None:
        for i in self.present_idx:
            if i < JOG_AXES:
                self._retarget(i)

    def _retarget(self, i: int) -> None:
        v = self._hw_velocity(i)
        if v is None:
            s = self.soft_speed[i]
            v = 0.0 if not s else math.copysign(self.speed_value_to_internal(i, s), s)
        self._set_jog_target(i, v)

    def _set_jog_target(self, i: int, v: float) -> None:
        if v and self.soft_limits and self._at_limit(i, v):
            v = 0.0
        if v == self.jog_target[i]:
            return
        cur = self.vel[i]
        self.jog_target[i] = v
        acc = 0.0
        if self.jog_time_ms > 0:
            acc = max(abs(cur), abs(v)) / self.jog_time_ms
        self.jog_acc[i] = acc if acc > 0 else self.amax[i]
        if v != 0.0 or cur != 0.0:
            self.jogging = True

    def _at_limit(self, i: int, v: float) -> bool:
        p = self.pos[i]
        if v > 0:
            return self.soft_max[i] is not None and p >= self.soft_max[i]
        return self.soft_min[i] is not None and p <= self.soft_min[i]

    def _step_jog(self) -> None:
        any_active = False
        pos, vel, tgt = self.pos, self.vel, self.jog_target
        for i in self.present_idx:
            vt = tgt[i]
            v = vel[i]
            if vt == 0.0 and v == 0.0:
                continue
            a = self.jog_acc[i]
            if v < vt:
                nv = min(vt, v + a)
            elif v > vt:
                nv = max(vt, v - a)
            else:
                nv = v
            p = pos[i]
            heading = nv if nv != 0.0 else v
            limit = None
            if self.soft_limits:
                if heading > 0:
                    limit = self.soft_max[i]
                elif heading < 0:
                    limit = self.soft_min[i]
            if limit is None:
                np = p + 0.5 * (v + nv)
            else:
                room = (limit - p) if heading > 0 else (p - limit)
                if room <= 0:
                    np, nv, hit = p, 0.0, v != 0.0
                else:
                    vb = math.sqrt(2.0 * a * room)
                    if abs(nv) > vb:
                        nv = math.copysign(vb, heading)
                    np = p + 0.5 * (v + nv)
                    hit = (np >= limit) if heading > 0 else (np <= limit)
                    if hit:
                        np, nv = limit, 0.0
                if hit or (nv == 0.0 and tgt[i] != 0.0 and room <= 0):
                    tgt[i] = 0.0
                if hit:
                    self.note("warning", f"soft limit: jog {AXES[i]}{'+' if heading > 0 else '-'}"
                                         f" stopped at {fmt_mm(limit)} {self.unit[i]}")
            pos[i] = np
            vel[i] = nv
            self.ipos[i] = round(np)
            if nv != 0.0 or tgt[i] != 0.0:
                any_active = True
        self.jogging = any_active

    # ---------------------------------------------------------- advance
    def advance(self, t_new: int) -> bool:
        """Advance 1 ms of motion, then apply what is due at tick t_new.
        Returns True when an axis may have moved."""
        moved = False
        if self.move is not None:
            self._step_move()
            moved = True
        elif self.jogging:
            self._step_jog()
            moved = True
        elif self.follow:
            moved = self._step_follow() or True
        if self.hw_dir and self.hw_last_write is not None \
                and t_new - self.hw_last_write >= self.watchdog_ms:
            self.note("warning", f"jog watchdog: 8635 was not written again within "
                                 f"{self.watchdog_ms} ms; jog stopped")
            self.hw_dir = 0
            self.hw_last_write = None
            self.jog_cmds.clear()
            self._retarget_all()
        if self.jog_cmds:
            self._apply_jog_cmds(t_new)
        if self.queue:
            self._start_due(t_new)
        return moved

    # ------------------------------------------------------ coordinates
    def program_position(self, i: int) -> int:
        return self.ipos[i] - self.offset[i]

    def velocity_report(self) -> tuple[int, ...]:
        """Velocities in 0.01 mm/s (the same tuple while they do not change)."""
        vel = self.vel
        if vel != self._vel_seen:
            self._vel_seen = list(vel)
            self._vel_report = tuple(round(v * 1000) for v in vel)
        return self._vel_report
