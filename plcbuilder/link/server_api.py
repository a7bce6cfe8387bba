"""myCNC's Server API on the simulated controller (docs/editors.md, "The
Server API").

A real myCNC controller answers a telnet-style text protocol that pendant
drivers and scripts use: one command a line, one reply a line. This offers
the same command set on an extra port of ``plcbuilder controller``
(``--server-api PORT``). Like myCNC's, it has no token: it listens on
loopback unless the user names another address.

Replies are ``OK`` followed by the values, or ``ERROR`` followed by the
reason; the connection stays open either way. Numbers may be decimal or
``0x`` hex; command names are not case sensitive.

The connections are served by the controller server's own selector loop
(:meth:`plcbuilder.link.server.Server.attach`): non-blocking sockets, lines of
at most :attr:`ServerApi.max_line` bytes (a longer one is answered with an
error and skipped), at most :attr:`ServerApi.lines_per_turn` commands of one
client per pass of the loop, and a client that does not read its replies is
not read either (then closed past :attr:`ServerApi.max_outbuf`), so a flood
never stalls the controller or the other clients.
"""

from __future__ import annotations

import selectors
import socket
from typing import Callable

from plcbuilder.controller import abi
from plcbuilder.controller.controller import Controller, ControllerError
from plcbuilder.link.pacing import SimulationDown
from plcbuilder.link.protocol import accept_all, listening_socket, refuse, send_pending

__all__ = ["ServerApi", "COMMANDS", "DEFAULT_PORT"]

#: myCNC's own Server API port.
DEFAULT_PORT = 4266


class ApiError(Exception):
    """A command that cannot be carried out; the reason goes back as ``ERROR reason``."""


def _int(text: str, what: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise ApiError(f"{what} must be a whole number (decimal or 0x hex), not {text!r}") from None


def _args(args: list[str], n: int, usage: str) -> list[str]:
    if len(args) != n:
        raise ApiError(f"usage: {usage}")
    return args


class _Client:
    __slots__ = ("sock", "peer", "inbuf", "out", "skipping", "mask", "closing")

    def __init__(self, sock: socket.socket, peer: str):
        self.sock = sock
        self.peer = peer
        self.inbuf = bytearray()
        self.out = bytearray()
        self.skipping = False       # inside a line that was too long: drop to its end
        self.mask = 0
        self.closing = False


# ===================================================================== the commands

def _axes_text(positions: dict[str, int]) -> str:
    return " ".join(f"{axis} {value / 100:.2f}" for axis, value in positions.items())


def _words(bits: int, count: int) -> str:
    words = max(1, -(-count // 32))
    return " ".join(f"0x{(bits >> (32 * k)) & 0xFFFFFFFF:08x}" for k in range(words))


class Commands:
    """The commands, one ``cmd_<name>`` each, run on the simulation thread
    with the controller; each returns the text after ``OK``."""

    #: name as shown by ``?`` -> (usage, what it does)
    HELP = {
        "RunPLC": ("RunPLC NAME [EPARAM]", "start a hardware procedure (M03, or an M-code number)"),
        "SetHWBinaryOutput": ("SetHWBinaryOutput PORT 0|1", "set an output"),
        "SetHWPWM": ("SetHWPWM CHANNEL VALUE", "set a PWM channel (0..7)"),
        "SetHWDAC": ("SetHWDAC CHANNEL VALUE", "set a DAC channel (0..7)"),
        "GetHWInputs": ("GetHWInputs", "the input pins, 32 a word, hex, pin 0 = bit 0 of the first"),
        "GetHWInputBit": ("GetHWInputBit PIN", "one input: 0 or 1"),
        "GetHWOutputs": ("GetHWOutputs", "the output pins, as GetHWInputs"),
        "GetHWOutputBit": ("GetHWOutputBit PORT", "one output: 0 or 1"),
        "GetHWPWM": ("GetHWPWM [CHANNEL]", "PWM channels 0..7 (or one)"),
        "GetHWDAC": ("GetHWDAC [CHANNEL]", "DAC channels 0..7 (or one)"),
        "GetHWADC": ("GetHWADC [CHANNEL]", "ADC channels 0..7 (or one)"),
        "GetIVariable": ("GetIVariable ADDRESS", "a global register, as gvarget reads it"),
        "GetGVariable": ("GetGVariable ADDRESS", "the same as GetIVariable"),
        "SetGVariable": ("SetGVariable ADDRESS VALUE", "write a global register, as gvarset"),
        "GetMachinePosition": ("GetMachinePosition", "machine position of each axis, mm"),
        "GetWorkPosition": ("GetWorkPosition", "program (work) position of each axis, mm"),
        "GetMCC": ("GetMCC", "the motion control code (register 6060): 0 moving, 77 idle"),
        "GetProcess": ("GetProcess", "the proc value and its name"),
        "GetRunning": ("GetRunning", "the hardware procedure running (or -) and the time"),
        "SetJog": ("SetJog x+|x-|xstop|…|stop", "jog an axis (refresh within 1 s, as a pendant does)"),
        "?": ("?", "list the commands"),
    }

    def __init__(self, controller: Controller):
        self.c = controller

    @property
    def m(self):
        return self.c.machine

    def run(self, name: str, args: list[str]) -> str:
        if name == "?":
            return " ".join(self.HELP)
        for known in self.HELP:
            if known.lower() == name.lower() and known != "?":
                return getattr(self, "cmd_" + known.lower())(args)
        raise ApiError(f"unknown command {name[:40]!r} (? lists the commands)")

    # ------------------------------------------------------------ procedures
    def cmd_runplc(self, args: list[str]) -> str:
        if len(args) not in (1, 2):
            raise ApiError("usage: RunPLC NAME [EPARAM]")
        eparam = _int(args[1], "EPARAM") if len(args) == 2 else 0
        name = args[0]
        if name.isdigit():
            started = self.c.start_mcode(int(name), eparam)
        else:
            self.c.start(name, eparam)
            started = name
        return f"{started} {eparam}"

    # ------------------------------------------------------------ outputs
    def cmd_sethwbinaryoutput(self, args: list[str]) -> str:
        port, value = _args(args, 2, "SetHWBinaryOutput PORT 0|1")
        port = self._pin(_int(port, "PORT"), self.m.output_count, "output")
        v = _int(value, "value")
        if v not in (0, 1):
            raise ApiError(f"an output is 0 or 1, not {v}")
        (self.m.portset if v else self.m.portclear)(port)
        return f"{port} {v}"

    def cmd_sethwpwm(self, args: list[str]) -> str:
        return self._set_channel(args, "SetHWPWM", abi.GVAR_HW_PWM0)

    def cmd_sethwdac(self, args: list[str]) -> str:
        return self._set_channel(args, "SetHWDAC", abi.GVAR_HW_DAC0)

    def _set_channel(self, args, name: str, base: int) -> str:
        ch, value = _args(args, 2, f"{name} CHANNEL VALUE")
        ch = self._pin(_int(ch, "CHANNEL"), 8, "channel")
        v = self._word(_int(value, "VALUE"))
        self.m.gvarset(base + ch, v)
        return f"{ch} {v}"

    # ------------------------------------------------------------ reading
    def cmd_gethwinputs(self, args: list[str]) -> str:
        _args(args, 0, "GetHWInputs")
        return _words(self.m.in_bits, self.m.input_count)

    def cmd_gethwoutputs(self, args: list[str]) -> str:
        _args(args, 0, "GetHWOutputs")
        return _words(self.m.out_bits, self.m.output_count)

    def cmd_gethwinputbit(self, args: list[str]) -> str:
        (pin,) = _args(args, 1, "GetHWInputBit PIN")
        pin = self._pin(_int(pin, "PIN"), self.m.input_count, "input")
        return str(self.m.portget(pin))

    def cmd_gethwoutputbit(self, args: list[str]) -> str:
        (pin,) = _args(args, 1, "GetHWOutputBit PORT")
        pin = self._pin(_int(pin, "PORT"), self.m.output_count, "output")
        return str((self.m.out_bits >> pin) & 1)

    def cmd_gethwpwm(self, args: list[str]) -> str:
        return self._channels(args, "GetHWPWM", "pwm")

    def cmd_gethwdac(self, args: list[str]) -> str:
        return self._channels(args, "GetHWDAC", "dac")

    def cmd_gethwadc(self, args: list[str]) -> str:
        return self._channels(args, "GetHWADC", "adc")

    def _channels(self, args, name: str, field: str) -> str:
        values = self.m.sample_fields()[field]
        if not args:
            return " ".join(str(v) for v in values)
        (ch,) = _args(args, 1, f"{name} [CHANNEL]")
        return str(values[self._pin(_int(ch, "CHANNEL"), len(values), "channel")])

    def cmd_getivariable(self, args: list[str]) -> str:
        (addr,) = _args(args, 1, "GetIVariable ADDRESS")
        return str(self.m.gvarget(self._word(_int(addr, "ADDRESS"))))

    cmd_getgvariable = cmd_getivariable

    def cmd_setgvariable(self, args: list[str]) -> str:
        addr, value = _args(args, 2, "SetGVariable ADDRESS VALUE")
        a, v = self._word(_int(addr, "ADDRESS")), self._word(_int(value, "VALUE"))
        self.m.gvarset(a, v)
        return f"{a} {self.m.gvarget(a)}"

    def cmd_getmachineposition(self, args: list[str]) -> str:
        _args(args, 0, "GetMachinePosition")
        return _axes_text(self.m.axis_positions())

    def cmd_getworkposition(self, args: list[str]) -> str:
        _args(args, 0, "GetWorkPosition")
        return _axes_text(self.m.program_positions())

    def cmd_getmcc(self, args: list[str]) -> str:
        _args(args, 0, "GetMCC")
        return str(self.m.motion_code)

    def cmd_getprocess(self, args: list[str]) -> str:
        _args(args, 0, "GetProcess")
        st = self.c.state()
        return f"{st.proc} {st.proc_name or '-'}"

    def cmd_getrunning(self, args: list[str]) -> str:
        _args(args, 0, "GetRunning")
        st = self.c.state()
        return f"{st.running or '-'} {st.t_ms}"

    # ------------------------------------------------------------ jog
    def cmd_setjog(self, args: list[str]) -> str:
        """``x+`` / ``x-`` jog X (bits 0..7 move +, 8..15 move -, as register
        8635), ``xstop`` stops X, ``stop`` stops every axis."""
        if not args:
            raise ApiError("usage: SetJog x+|x-|xstop|…|stop (several may follow)")
        bits = self.m.gvarget(abi.JOG) & 0xFFFF
        for word in args:
            w = word.lower()
            if w == "stop":
                bits = 0
                continue
            axis, how = w[:1].upper(), w[1:]
            if axis not in abi.AXES[:8] or how not in ("+", "-", "stop"):
                raise ApiError(f"SetJog: {word!r} is not AXIS+, AXIS- or AXISstop "
                               f"(axes {' '.join(a.lower() for a in abi.AXES[:8])})")
            i = abi.AXES.index(axis)
            bits &= ~((1 << i) | (1 << (8 + i)))
            if how == "+":
                bits |= 1 << i
            elif how == "-":
                bits |= 1 << (8 + i)
        self.m.gvarset(abi.JOG, bits)
        return f"0x{bits:04x}"

    # ------------------------------------------------------------ checks
    @staticmethod
    def _pin(n: int, count: int, what: str) -> int:
        if not 0 <= n < count:
            raise ApiError(f"no {what} {n} (0..{count - 1})")
        return n

    @staticmethod
    def _word(v: int) -> int:
        if not -(1 << 31) <= v < (1 << 32):
            raise ApiError(f"{v} is not a 32-bit value")
        return v - (1 << 32) if v >= 1 << 31 else v


COMMANDS = tuple(Commands.HELP)


# ===================================================================== the network

class ServerApi:
    """The Server API's listener and connections, served by the loop of a
    :class:`~plcbuilder.link.server.Server` (``server.attach(api)``)."""

    max_line = 1024
    lines_per_turn = 16
    max_clients = 16
    #: Reply bytes waiting for a client above which it is not read, and closed above max_outbuf.
    read_pause = 64 << 10
    max_outbuf = 1 << 20

    def __init__(self, sim, host: str = "127.0.0.1", port: int = DEFAULT_PORT):
        self.sim = sim
        lsock = self._lsock = listening_socket(host, port, 16)
        self.address: tuple[str, int] = lsock.getsockname()[:2]
        self._clients: dict[int, _Client] = {}
        self._ready: list[_Client] = []          # whole lines waiting for the next pass
        self._loop = None
        self.stats = {"accepted": 0, "commands": 0, "errors": 0, "long_lines": 0, "closed": 0}

    # ------------------------------------------------------------ the loop's side
    def attach_to(self, loop) -> None:
        """Called by Server.attach: register the listener with its selector."""
        self._loop = loop
        loop.watch(self._lsock, selectors.EVENT_READ, self._on_accept)

    @property
    def pending(self) -> bool:
        """Work left for the next pass (the loop does not sleep meanwhile)."""
        return bool(self._ready)

    def on_pass(self) -> None:
        ready, self._ready = self._ready, []
        for client in ready:
            self._serve(client)

    def close(self) -> None:
        for client in list(self._clients.values()):
            self._drop(client)
        try:
            self._loop.unwatch(self._lsock)
        except Exception:  # noqa: BLE001 - the selector may be closed already
            pass
        try:
            self._lsock.close()
        except OSError:
            pass

    # ------------------------------------------------------------ connections
    def _on_accept(self, _sock, _mask) -> None:
        for sock, peer in accept_all(self._lsock):
            self.stats["accepted"] += 1
            if len(self._clients) >= self.max_clients:
                refuse(sock, f"ERROR too many Server API clients ({self.max_clients})\r\n"
                       .encode())
                continue
            client = _Client(sock, peer)
            self._clients[sock.fileno()] = client
            self._update(client)

    def _on_ready(self, client: _Client, mask: int) -> None:
        if mask & selectors.EVENT_WRITE:
            self._write(client)
        if mask & selectors.EVENT_READ and not client.closing:
            self._read(client)
        if client.sock.fileno() in self._clients:
            self._update(client)

    def _read(self, client: _Client) -> None:
        try:
            data = client.sock.recv(16384)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._drop(client)
            return
        if not data:
            client.closing = True
            if client.inbuf.strip() and not client.skipping and b"\n" not in client.inbuf:
                client.inbuf += b"\n"            # the last line without its newline
            self._serve(client)
            return
        client.inbuf += data
        self._serve(client)

    def _serve(self, client: _Client) -> None:
        """Answer the whole lines buffered, a turn's worth at most."""
        if client.sock.fileno() not in self._clients:
            return
        n = 0
        while n < self.lines_per_turn and len(client.out) < self.read_pause:
            nl = client.inbuf.find(b"\n")
            if nl < 0:
                if len(client.inbuf) > self.max_line:
                    if not client.skipping:
                        self._long_line(client)
                    client.skipping = True
                    del client.inbuf[:]
                break
            line = bytes(client.inbuf[:nl])
            del client.inbuf[:nl + 1]
            if client.skipping:
                client.skipping = False          # the end of the long line
                continue
            if len(line) > self.max_line:
                self._long_line(client)
                continue
            n += 1
            self._reply(client, self.answer(line))
        if client.inbuf.find(b"\n") >= 0 and client not in self._ready:
            self._ready.append(client)           # the rest: next pass
        elif client.closing and client.inbuf.strip() and not client.skipping:
            client.inbuf += b"\n"               # the last line, once the rest is answered
            self._ready.append(client)
        self._write(client)
        if client.sock.fileno() in self._clients:
            self._update(client)

    def _long_line(self, client: _Client) -> None:
        self.stats["long_lines"] += 1
        self._reply(client, f"ERROR line longer than {self.max_line} bytes; ignored")

    def answer(self, raw: bytes) -> str:
        """One command line -> its reply line (without the line end)."""
        text = raw.decode("utf-8", "replace").strip().strip("\x00")
        if not text:
            return "ERROR empty command (? lists the commands)"
        words = text.split()
        self.stats["commands"] += 1
        commands = Commands(self.sim.controller)
        try:
            result = self.sim.call(lambda: commands.run(words[0], words[1:]), timeout=5.0)
        except ApiError as exc:
            self.stats["errors"] += 1
            return f"ERROR {exc}"
        except ControllerError as exc:
            self.stats["errors"] += 1
            return f"ERROR {exc}"
        except (SimulationDown, TimeoutError) as exc:
            self.stats["errors"] += 1
            return f"ERROR the controller is not running ({exc})"
        return f"OK {result}" if result else "OK"

    def _reply(self, client: _Client, text: str) -> None:
        client.out += text.replace("\r", " ").replace("\n", " ").encode("utf-8") + b"\r\n"
        if len(client.out) > self.max_outbuf:
            self._drop(client)

    def _write(self, client: _Client) -> None:
        if not send_pending(client.sock, client.out, 65536):
            self._drop(client)
            return
        if not client.out and client.closing and client not in self._ready:
            self._drop(client)                   # it said all it had to say, and has it all

    def _update(self, client: _Client) -> None:
        mask = 0
        if not client.closing and len(client.out) < self.read_pause and client not in self._ready:
            mask |= selectors.EVENT_READ
        if client.out:
            mask |= selectors.EVENT_WRITE
        if mask == client.mask:
            return
        cb: Callable = lambda _s, m, c=client: self._on_ready(c, m)  # noqa: E731
        if client.mask and mask:
            self._loop.rewatch(client.sock, mask, cb)
        elif mask:
            self._loop.watch(client.sock, mask, cb)
        else:
            self._loop.unwatch(client.sock)
        client.mask = mask

    def _drop(self, client: _Client) -> None:
        if self._clients.pop(client.sock.fileno(), None) is None:
            return
        self.stats["closed"] += 1
        if client.mask:
            try:
                self._loop.unwatch(client.sock)
            except Exception:  # noqa: BLE001
                pass
        client.mask = 0
        if client in self._ready:
            self._ready.remove(client)
        try:
            client.sock.close()
        except OSError:
            pass
