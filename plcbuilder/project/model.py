"""The project folder (docs/projects.md) and its settings file.

A project is a folder::

    plcbuilder.toml        settings (optional: defaults when missing)
    hardware/*.plc         hardware procedures (M03.plc is what M03 starts)
    software/*.plc         software procedures (__NAME: system procedures)
    include/pins.h         headers searched by #include (after the procedure's folder)
    plc-variables.xml      initial values of var00..var15
    machine.toml           the simulated machine (path set in the settings)
    build/                 Build All's output: NAME.bin, eeprom.rom, .cache.json

The settings file::

    name = "my machine"            # default: the folder's name
    machine = "machine.toml"       # relative to the project folder
    target = "mycnc"               # the controller: mycnc, huazhong or tgmotion (docs/targets.md)

    [limits]                       # code size limits in bytes
    hw_proc = 512
    hw_total = 8192
    sw_proc = 16384

    [controller]
    address = "127.0.0.1:5700"     # the controller the IDE/CLI talk to ("" = the embedded one)

    [build]
    strict = false                 # build with --strict (controller compatibility)
    include = ["../shared"]        # more folders #include searches (relative to the project)

    [huazhong]
    parameters = "parameters.toml" # the P registers' values

    [tgmotion]
    cycle_time_us = 500            # 250, 500 or 1000
    cycle_time_program_01_us = 1000   # at least 100, no upper bound (also _02_, _03_)
    oscilloscope = ["in 9", "Program.x"]   # what it samples after Program_04
    instruction_ns = 20            # modelled execution time of one instruction

#include finds headers in the procedure's folder, include/, the folders of
[build] include, then the built-in headers; a header must lie inside the
project (links resolved) or inside a folder named by [build] include or
--include: see plcbuilder.lang.preprocess.

Every problem with the settings raises :class:`ProjectError` naming the file,
the line and the key.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from plcbuilder._support.records import dataclass, field, replace
from plcbuilder._support.files import atomic_write, read_bounded
from plcbuilder._support.toml_errors import TomlLocator, decode_error
from plcbuilder._support.toml_errors import loads as toml_loads
from plcbuilder.bytecode import targets as T
from plcbuilder.bytecode.kind import Kind
from plcbuilder.image.limits import MAX_LIMIT, Limits
from plcbuilder.lang.options import CompileOptions

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional, Union

SETTINGS_FILE = "plcbuilder.toml"
HARDWARE_DIR = "hardware"
SOFTWARE_DIR = "software"
INCLUDE_DIR = "include"
BUILD_DIR = "build"
VARIABLES_FILE = "plc-variables.xml"
DEFAULT_MACHINE = "machine.toml"
IMAGE_FILE = "eeprom.rom"
DEFAULT_PARAMETERS = "parameters.toml"
SOURCE_SUFFIX = ".plc"
MAX_SETTINGS_BYTES = 1 << 20


def looks_like_project(path: Union[str, Path]) -> bool:
    """True for a folder with a settings file or a hardware/ or software/ folder:
    what a project has. (Project.open accepts any folder, with the defaults.)"""
    p = Path(path)
    return p.is_dir() and ((p / SETTINGS_FILE).is_file() or (p / HARDWARE_DIR).is_dir()
                           or (p / SOFTWARE_DIR).is_dir())


def not_a_project(path: Union[str, Path]) -> Optional[str]:
    """Why the folder ``path`` is not a project, or None when it is one (or is no
    folder: opening it says so): what Build All and the debug adapter's launch
    say before they write anything there."""
    p = Path(path)
    if not p.is_dir() or looks_like_project(p):
        return None
    return (f"not a project: it has no {SETTINGS_FILE}, {HARDWARE_DIR}/ or {SOFTWARE_DIR}/ "
            "(plcbuilder new DIR makes one in a new or empty folder)")


class ProjectError(ValueError):
    """A project that cannot be opened or used; ``str()`` reads ``FILE:LINE: what``."""

    def __init__(self, message: str, file: Optional[Union[str, Path]] = None,
                 line: Optional[int] = None, key: Optional[str] = None):
        self.message = message
        self.file = str(file) if file is not None else None
        self.line = line
        self.key = key
        where = ""
        if self.file is not None:
            where = f"{self.file}:{line}: " if line is not None else f"{self.file}: "
        super().__init__(f"{where}{key + ': ' if key else ''}{message}")


# ---------------------------------------------------------------- settings

@dataclass(frozen=True)
class Settings:
    name: str = ""
    machine: str = DEFAULT_MACHINE
    limits: Limits = field(default_factory=Limits)
    controller_address: str = ""
    strict: bool = False
    include: tuple[str, ...] = ()      # [build] include: more include folders
    target: str = T.MYCNC              # the controller the project is for (docs/targets.md)
    parameters: str = DEFAULT_PARAMETERS   # [huazhong] parameters: the P registers' file
    cycle_time_us: int = 500           # [tgmotion]
    program_periods_us: tuple[int, int, int] = (1000, 1000, 1000)
    instruction_ns: int = T.TGM_DEFAULT_INSTRUCTION_NS
    oscilloscope: tuple[str, ...] = ()     # [tgmotion] the signals it samples (() default)

    def to_toml(self) -> str:
        """The settings file's text (every key written, with comments)."""
        def line(key: str, value: str, comment: str) -> str:
            text = f"{key} = {value}"
            return text.ljust(27) + (" " if len(text) >= 27 else "") + f"# {comment}\n"
        lim = self.limits
        return ("# PLC Builder project settings (see docs/projects.md in PLC Builder)\n"
                + line("name", _toml_str(self.name), "the project's name")
                + line("machine", _toml_str(self.machine), "the simulated machine's file")
                + (line("target", _toml_str(self.target), "the controller: mycnc, huazhong or "
                        "tgmotion (docs/targets.md)") if self.target != T.MYCNC else "")
                + "\n[limits]\n"
                + line("hw_proc", str(lim.hw_proc), "bytes of code of one hardware procedure")
                + line("hw_total", str(lim.hw_total), "... of all hardware procedures together")
                + line("sw_proc", str(lim.sw_proc), "... of one software procedure")
                + "\n[controller]\n"
                + line("address", _toml_str(self.controller_address),
                       "HOST:PORT of a running controller; empty: the embedded one")
                + "\n[build]\n"
                + line("strict", "true" if self.strict else "false",
                       "controller compatibility: only what the myCNC manual shows")
                + line("include", "[" + ", ".join(_toml_str(d) for d in self.include) + "]",
                       "more #include folders (may be outside the project)")
                + self._target_toml(line))

    def _target_toml(self, line) -> str:
        """The target's keys: written only for a target other than mycnc (a
        myCNC project's file stays as it always was)."""
        if self.target == T.MYCNC:
            return ""
        out = ""
        if self.target == T.HUAZHONG:
            out += ("\n[huazhong]\n"
                    + line("parameters", _toml_str(self.parameters), "the P registers' values"))
        if self.target == T.TGMOTION:
            out += ("\n[tgmotion]\n"
                    + line("cycle_time_us", str(self.cycle_time_us), "250, 500 or 1000")
                    + "".join(line(f"cycle_time_program_0{i + 1}_us", str(v), "at least 100 (µs)")
                              for i, v in enumerate(self.program_periods_us))
                    + line("instruction_ns", str(self.instruction_ns),
                           "modelled time of one instruction")
                    + line("oscilloscope", "[" + ", ".join(_toml_str(x) for x in self.oscilloscope)
                           + "]", "signals sampled after Program_04: \"in 9\", "
                                  "\"gvar 2000001\", \"Program.x\" (empty: in/out word 0)"))
        return out


def _toml_str(s: str) -> str:
    out = ['"']
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


_SCHEMA: dict[str, dict[str, type]] = {
    "": {"name": str, "machine": str, "target": str},
    "limits": {"hw_proc": int, "hw_total": int, "sw_proc": int},
    "controller": {"address": str},
    "build": {"strict": bool, "include": list},
    "huazhong": {"parameters": str},
    "tgmotion": {"cycle_time_us": int, "cycle_time_program_01_us": int,
                 "cycle_time_program_02_us": int, "cycle_time_program_03_us": int,
                 "instruction_ns": int, "oscilloscope": list},
}


def _line_of(text: str, table: str, key: Optional[str]) -> Optional[int]:
    """The line where [table] key = … is (or the table header), for messages."""
    path = tuple(p for p in (table, key) if p)
    return TomlLocator(text).line_of(path) if path else None


def parse_settings(text: str, file: Union[str, Path] = SETTINGS_FILE,
                   default_name: str = "") -> Settings:
    """Settings from the text of a plcbuilder.toml; raises ProjectError."""
    try:
        doc = toml_loads(text)
    except ValueError as exc:                # tomllib.TOMLDecodeError
        msg, line = decode_error(exc, text)
        raise ProjectError(f"not valid TOML: {msg}", file, line) from None
    values: dict[str, object] = {}
    for key, value in doc.items():
        if key in _SCHEMA and key != "":
            if not isinstance(value, dict):
                raise ProjectError(f"[{key}] must be a table", file, _line_of(text, "", key), key)
            for sub, v in value.items():
                _check(text, file, key, sub, v)
                values[f"{key}.{sub}"] = v
        else:
            _check(text, file, "", key, value)
            values[key] = value
    lim = Limits()
    limits = Limits(hw_proc=values.get("limits.hw_proc", lim.hw_proc),
                    hw_total=values.get("limits.hw_total", lim.hw_total),
                    sw_proc=values.get("limits.sw_proc", lim.sw_proc))
    machine = values.get("machine", DEFAULT_MACHINE)
    if not machine.strip():
        raise ProjectError("machine must name a file", file, _line_of(text, "", "machine"),
                           "machine")
    address = values.get("controller.address", "")
    if address and not re.fullmatch(r"\[?[A-Za-z0-9_.:\-]+\]?:\d{1,5}", address):
        raise ProjectError(f"address must be HOST:PORT, is {address!r}", file,
                           _line_of(text, "controller", "address"), "controller.address")
    include = values.get("build.include", [])
    for d in include:
        if not isinstance(d, str) or not d.strip():
            raise ProjectError("include must be a list of folder names (strings)", file,
                               _line_of(text, "build", "include"), "build.include")
    target = values.get("target", T.MYCNC)
    if target not in T.TARGETS:
        raise ProjectError(f"unknown target {target!r} (one of {', '.join(T.TARGETS)})", file,
                           _line_of(text, "", "target"), "target")
    parameters = values.get("huazhong.parameters", DEFAULT_PARAMETERS)
    if not parameters.strip():
        raise ProjectError("parameters must name a file", file,
                           _line_of(text, "huazhong", "parameters"), "huazhong.parameters")
    cycle = values.get("tgmotion.cycle_time_us", 500)
    if cycle not in T.TGM_CYCLE_TIMES:
        raise ProjectError(f"must be 250, 500 or 1000 (µs, as TG Motion's Cycle_Time), is {cycle}",
                           file, _line_of(text, "tgmotion", "cycle_time_us"),
                           "tgmotion.cycle_time_us")
    lo = T.TGM_PERIOD_MIN
    periods = []
    for i in (1, 2, 3):
        key = f"cycle_time_program_0{i}_us"
        v = values.get(f"tgmotion.{key}", 1000)
        if v < lo:
            raise ProjectError(f"must be at least {lo} µs (no upper bound), is {v}", file,
                               _line_of(text, "tgmotion", key), f"tgmotion.{key}")
        periods.append(v)
    ns = values.get("tgmotion.instruction_ns", T.TGM_DEFAULT_INSTRUCTION_NS)
    if not 1 <= ns <= 1_000_000:
        raise ProjectError(f"must be from 1 to 1000000 ns, is {ns}", file,
                           _line_of(text, "tgmotion", "instruction_ns"), "tgmotion.instruction_ns")
    scope = values.get("tgmotion.oscilloscope", [])
    where = (file, _line_of(text, "tgmotion", "oscilloscope"), "tgmotion.oscilloscope")
    if len(scope) > T.TGM_OSC_SIGNALS_MAX:
        raise ProjectError(f"{len(scope)} signals: at most {T.TGM_OSC_SIGNALS_MAX}", *where)
    for sig in scope:
        try:
            T.parse_signal(sig)
        except T.ScopeError as exc:
            raise ProjectError(str(exc), *where) from None
    return Settings(name=values.get("name", default_name) or default_name, machine=machine,
                    limits=limits, controller_address=address,
                    strict=values.get("build.strict", False), include=tuple(include),
                    target=target, parameters=parameters, cycle_time_us=cycle,
                    program_periods_us=tuple(periods), instruction_ns=ns,
                    oscilloscope=tuple(scope))


def _check(text: str, file, table: str, key: str, value) -> None:
    label = f"{table}.{key}" if table else key
    schema = _SCHEMA[table]
    if key not in schema:
        known = ", ".join(sorted((f"{table}.{k}" if table else k) for k in schema))
        where = f"[{table}] " if table else ""
        raise ProjectError(f"unknown setting {where}{key!r} (known here: {known})", file,
                           _line_of(text, table, key), label)
    want = schema[key]
    if type(value) is not want:
        raise ProjectError(f"must be {_type_word(want)}, is {_type_word(type(value))} {value!r}",
                           file, _line_of(text, table, key), label)
    if want is int and table == "limits" and not 0 < value <= MAX_LIMIT:
        raise ProjectError(f"must be from 1 to {MAX_LIMIT} bytes, is {value}", file,
                           _line_of(text, table, key), label)


def _type_word(t: type) -> str:
    return {str: "a string", int: "a whole number", bool: "true or false",
            float: "a number", dict: "a table", list: "a list"}.get(t, t.__name__)


# ----------------------------------------------------------------- project

def kind_of(path: Union[str, Path], software: bool = False) -> Kind:
    """A procedure's kind: software when asked for, or when its file sits in a
    folder named ``software``; hardware otherwise."""
    if software or Path(path).parent.name == SOFTWARE_DIR:
        return Kind.SOFTWARE
    return Kind.HARDWARE


@dataclass(frozen=True)
class Procedure:
    name: str          # the file stem: what the M-code / the name starts
    kind: Kind
    path: Path

    @property
    def system(self) -> bool:
        """A software procedure started only by an event or by hand (__NAME)."""
        return self.name.startswith("__")


@dataclass
class Project:
    root: Path
    settings: Settings
    settings_found: bool = True

    # --------------------------------------------------------------- open
    @classmethod
    def open(cls, path: Union[str, Path], *, existing: bool = False) -> "Project":
        """Open a project folder (or its plcbuilder.toml). A missing settings
        file means the defaults; a bad one raises ProjectError (file, line).
        ``existing``: a folder that is not a project (:func:`not_a_project`)
        raises ProjectError too, rather than being a project with no procedures
        (what building or launching asks: they would write into it)."""
        p = Path(path)
        if p.name == SETTINGS_FILE and p.is_file():
            p = p.parent
        if not p.exists():
            raise ProjectError("no such folder", p)
        if not p.is_dir():
            raise ProjectError("a project is a folder (with hardware/ and software/), "
                               "this is a file", p)
        why = not_a_project(p) if existing else None
        if why is not None:
            raise ProjectError(why, p)
        default_name = p.resolve().name
        sp = p / SETTINGS_FILE
        if not sp.exists():
            return cls(p, Settings(name=default_name), settings_found=False)
        try:
            raw = read_bounded(sp, MAX_SETTINGS_BYTES, "settings file")
        except OSError as exc:
            raise ProjectError(f"cannot read: {exc.strerror or exc}", sp) from None
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            line = raw[:exc.start].count(b"\n") + 1
            raise ProjectError("not UTF-8 text", sp, line) from None
        return cls(p, parse_settings(text, sp, default_name))

    @classmethod
    def find_for(cls, path: Union[str, Path]) -> Optional["Project"]:
        """The project a source file belongs to: the file sits in the ``hardware/``
        or ``software/`` folder of a folder with a settings file or an ``include/``
        folder. None when it is not in a project; raises ProjectError when the
        project's settings cannot be read."""
        path = Path(path)
        if path.parent.name not in (HARDWARE_DIR, SOFTWARE_DIR):
            return None
        root = path.parent.parent
        if not (root / SETTINGS_FILE).is_file() and not (root / INCLUDE_DIR).is_dir():
            return None
        return cls.open(root)

    def compile_options(self, path: Union[str, Path], *, software: bool = False,
                        strict: Optional[bool] = None,
                        extra_includes: tuple = ()) -> CompileOptions:
        """How Build All compiles the file at ``path``: its kind by its folder (or
        software when asked), the include folders (``extra_includes`` first, then the
        project's), the project's size limit for that kind, and strict as the
        project's settings say unless ``strict`` says otherwise."""
        kind = kind_of(path, software)
        dirs = list(extra_includes)
        dirs += [d for d in self.include_dirs() if d not in dirs]
        strict = self.settings.strict if strict is None else strict
        return CompileOptions(kind=kind, strict=strict, include_dirs=tuple(dirs),
                              code_limit=self.limits.proc_limit(kind), root=self.root,
                              target=self.settings.target)

    # -------------------------------------------------------------- paths
    @property
    def name(self) -> str:
        return self.settings.name

    @property
    def settings_path(self) -> Path:
        return self.root / SETTINGS_FILE

    @property
    def hardware_dir(self) -> Path:
        return self.root / HARDWARE_DIR

    @property
    def software_dir(self) -> Path:
        return self.root / SOFTWARE_DIR

    @property
    def include_dir(self) -> Path:
        return self.root / INCLUDE_DIR

    @property
    def build_dir(self) -> Path:
        return self.root / BUILD_DIR

    @property
    def image_path(self) -> Path:
        return self.build_dir / IMAGE_FILE

    @property
    def variables_path(self) -> Path:
        return self.root / VARIABLES_FILE

    @property
    def machine_path(self) -> Path:
        return self.root / self.settings.machine

    @property
    def parameters_path(self) -> Path:
        """The Huazhong target's P registers file."""
        return self.root / self.settings.parameters

    @property
    def target(self) -> str:
        return self.settings.target

    def target_settings(self) -> dict:
        """What the controller needs to run this project's target (the keyword
        arguments of controller.targets.TargetConfig); reads the Huazhong
        parameters file (ProjectError naming its line when it is wrong)."""
        from plcbuilder.project.parameters import load_parameters
        st = self.settings
        out = {"name": st.target}
        if st.target == T.HUAZHONG:
            out["parameters"] = tuple(load_parameters(self.parameters_path))
        if st.target == T.TGMOTION:
            out.update(cycle_time_us=st.cycle_time_us,
                       program_periods_us=tuple(st.program_periods_us),
                       instruction_ns=st.instruction_ns, scope=tuple(st.oscilloscope))
        return out

    @property
    def limits(self) -> Limits:
        return self.settings.limits

    def dir_for(self, kind: Kind) -> Path:
        return self.hardware_dir if Kind(kind) is Kind.HARDWARE else self.software_dir

    def include_dirs(self) -> tuple[Path, ...]:
        """Folders #include searches after the procedure's own folder: include/,
        then the folders of ``[build] include`` (relative to the project); the
        built-in headers come last, by the compiler."""
        dirs = [self.include_dir] + [self.root / d for d in self.settings.include]
        out: list[Path] = []
        for d in dirs:
            if d.is_dir() and d not in out:
                out.append(d)
        return tuple(out)

    # --------------------------------------------------------- procedures
    def procedures(self, kind: Optional[Kind] = None) -> list[Procedure]:
        """Every *.plc of hardware/ and software/ (read from disk on each call),
        hardware first, each sorted by name."""
        out = []
        for k in (Kind.HARDWARE, Kind.SOFTWARE):
            if kind is not None and Kind(kind) is not k:
                continue
            folder = self.dir_for(k)
            try:
                with os.scandir(folder) as it:      # (a file's type without a stat a file)
                    entries = [e for e in it if e.name.endswith(SOURCE_SUFFIX)
                               and not e.name.startswith(".") and _is_file(e)]
            except (FileNotFoundError, NotADirectoryError):
                continue
            except OSError as exc:
                raise ProjectError(f"cannot list: {exc.strerror or exc}", folder) from None
            for e in entries:
                out.append(Procedure(e.name[:-len(SOURCE_SUFFIX)], k, folder / e.name))
        out.sort(key=lambda pr: (pr.kind, pr.name))
        return out

    def procedure(self, name: str, kind: Optional[Kind] = None) -> Optional[Procedure]:
        for p in self.procedures(kind):
            if p.name == name:
                return p
        return None

    def new_procedure_path(self, name: str, kind: Kind) -> Path:
        return self.dir_for(kind) / f"{name}{SOURCE_SUFFIX}"

    # ------------------------------------------------------------- saving
    def save_settings(self, settings: Optional[Settings] = None) -> None:
        """Write the settings file atomically (every key, with comments)."""
        if settings is not None:
            self.settings = settings
        atomic_write(self.settings_path, self.settings.to_toml())
        self.settings_found = True

    def with_settings(self, **changes) -> "Project":
        return Project(self.root, replace(self.settings, **changes), self.settings_found)


def _is_file(entry: "os.DirEntry") -> bool:
    """Path.is_file() of a folder entry (a link to a file is one; an entry
    that cannot be examined is none)."""
    try:
        return entry.is_file()
    except OSError:
        return False
