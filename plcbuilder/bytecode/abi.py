"""The controller's ABI: the myCNC tables of codes and register addresses.

One place for every name with a value in the myCNC PLC manual (the seed).
The compiler reads these as built-in names; the controller reads them to decode
and name what happens (messages, exit codes, proc states, registers).

Where the manual gives one name two values, the first table wins
(``GVAR_HW_PWM0`` is 7278, not 7270). Where several names share one value
(``PLCCMD_WATCHBIT1_ON`` and ``PLCCMD_TRIGGER1_ON``), looking a value up by
name gives the first name listed.
"""

from __future__ import annotations

from plcbuilder.bytecode import softmc

TYPE_CHECKING = False               # (typing is not imported at run time: start-up)
if TYPE_CHECKING:
    from typing import Optional

# ----------------------------------------------------------------- VM limits
#: (one place: the interpreters fault past them, the checker warns of them)
#: instructions one procedure may run in one tick
TICK_BUDGET = 100_000
#: how deep CALLs may nest
MAX_CALL_DEPTH = 16
#: values on the evaluation stack
STACK_LIMIT = 1024

# --------------------------------------------------------------- PLC defines
PLCCMD: dict[str, int] = {
    "PLCCMD_MOTION_CONTINUE": 1001,
    "PLCCMD_MOTION_SKIP": 1002,
    "PLCCMD_MOTION_SOFT_SKIP": 1003,
    "PLCCMD_MOTION_PAUSE": 1004,
    "PLCCMD_PLC_PAUSE": 1005,
    "PLCCMD_PLC_FORK_PAUSE": 1006,
    "PLCCMD_LINE_SOFT_STOP": 1007,
    "PLCCMD_LINE_STOP": 1008,
    "PLCCMD_REPLY_TO_MYCNC": 1100,
    "PLCCMD_SET_CNC_VAR": 1010,
    "PLCCMD_SET_THC_VAR": 1011,
    "PLCCMD_SET_DEVICE_VAR16": 1012,
    "PLCCMD_SET_DEVICE_VAR32": 1014,
    "PLCCMD_SET_CNC_EXTVAR": 1020,
    "PLCCMD_MOTION_ABORT": 1032,
    "PLCCMD_MOTION_BREAK": 1033,
    "PLCCMD_SAVE_POS": 1040,
    "PLCCMD_THC_START": 1050,
    "PLCCMD_THC_STOP": 1051,
    "PLCCMD_THC_PAUSE": 1052,
    "PLCCMD_THC_CONTINUE": 1053,
    "PLCCMD_WATCHBIT1_ON": 1060,
    "PLCCMD_WATCHBIT2_ON": 1061,
    "PLCCMD_WATCHBIT3_ON": 1062,
    "PLCCMD_WATCHBIT4_ON": 1063,
    "PLCCMD_TRIGGER1_ON": 1060,
    "PLCCMD_TRIGGER2_ON": 1061,
    "PLCCMD_TRIGGER3_ON": 1062,
    "PLCCMD_TRIGGER4_ON": 1063,
    "PLCCMD_TRIGGER1_OFF": 1064,
    "PLCCMD_TRIGGER2_OFF": 1065,
    "PLCCMD_TRIGGER3_OFF": 1066,
    "PLCCMD_TRIGGER4_OFF": 1067,
    "PLCCMD_WATCHBIT1_OFF": 1064,
    "PLCCMD_WATCHBIT2_OFF": 1065,
    "PLCCMD_WATCHBIT3_OFF": 1066,
    "PLCCMD_WATCHBIT4_OFF": 1067,
    "PLCCMD_WATCHBIT5_ON": 1068,
    "PLCCMD_WATCHBIT6_ON": 1069,
    "PLCCMD_WATCHBIT7_ON": 1070,
    "PLCCMD_WATCHBIT8_ON": 1071,
    "PLCCMD_WATCHBIT5_OFF": 1072,
    "PLCCMD_WATCHBIT6_OFF": 1073,
    "PLCCMD_WATCHBIT7_OFF": 1074,
    "PLCCMD_WATCHBIT8_OFF": 1075,
    "PLCCMD_WAIT_FOR_CAMERA": 1090,
    "PLCCMD_WAIT_VARSET": 1091,
    "PLCCMD_WAIT_VARCLEAR": 1092,
    "PLCCMD_CAMERA_START": 1093,
    "PLCCMD_CAMERA_FINISH": 1094,
    "PLCCMD_PLC_DEBUG": 1098,
    "PLCCMD_PLC_RESTART": 1099,
    "PLCCMD_MODBUS_SPINDLE_SPEED": 1230,
    "PLCCMD_MODBUS_SPINDLE_CMD": 1231,
    "PLCCMD_SET_PIDTIME": 1240,
}

PLC_BROADCAST: dict[str, int] = {
    **{f"PLC_BROADCAST_INQUIRY{i}": 1200 + i for i in range(16)},
    "PLC_BROADCAST_OK": 1220,
    "PLC_BROADCAST_ABORTED": 1221,
}

PLC_MESSAGE: dict[str, int] = {
    "PLC_MESSAGE_PLASMA_OK": 101,
    "PLC_MESSAGE_WATCHBIT_ACTION": 110,
    "PLC_MESSAGE_SPINDLE_SPEED_CHANGED": 120,
    "PLC_MESSAGE_PULL_OUT_TOOL": 130,
    "PLC_MESSAGE_SPINDLE_TURNING": 131,
    "PLC_MESSAGE_ENCODER_DATA": 140,
    "PLC_MESSAGE_GVAR_VALUE": 141,
    "PLC_MESSAGE_UID": 142,
    "PLC_MESSAGE_HCONTROL_OFFSET": 144,
    "PLC_MESSAGE_TANGENT_ANGLE": 145,
    "PLC_MESSAGE_USER": 146,
    "PLC_MESSAGE_HCONTROL_JSPEED": 147,
    "PLC_MESSAGE_HCONTROL_DC": 148,
    "PLC_MESSAGE_ASK_RECALC": 150,
    "PLC_MESSAGE_SOFTLIMIT_STOP": 151,
    "PLC_MESSAGE_GVARSET": 153,
    "PLC_MESSAGE_IHC_NOT_CONNECTED": 155,
    "PLC_MESSAGE_IHC_ERROR": 156,
    "PLC_MESSAGE_LATHE_GEAR": 160,
    "PLC_MESSAGE_ERR_VM": -1,
    "PLC_MESSAGE_ERR_ROMFS": -2,
    "PLC_MESSAGE_MOTION_BUFFER_EMPTY": -5,
    "PLC_MESSAGE_ERR_SENSOR_COOLANT": -10,
    "PLC_MESSAGE_ERR_SENSOR_AIR": -11,
    "PLC_MESSAGE_ERR_SENSOR_GAS": -12,
    "PLC_MESSAGE_ERR_SENSOR_OXYGEN": -13,
    "PLC_MESSAGE_ERR_SENSOR_PLASMA": -14,
    "PLC_MESSAGE_ERR_PROBING": -15,
    "PLC_MESSAGE_ERR_PLASMA_FAIL": -20,
    "PLC_MESSAGE_ERR_PLASMA_TIMEOUT": -21,
    "PLC_MESSAGE_PRESSED_ALARM_KEY": -30,
    "PLC_MESSAGE_PRESSED_STOP_KEY": -31,
    "PLC_MESSAGE_MOTOR_SHORTED": -35,
}

MAPPED_OUT: dict[str, int] = {
    "MAPPED_OUT_THC_LOWSPEED": 63,
    "MAPPED_OUT_LOW_MOTOR_CURRENT": 65,
}

# ------------------------------------------------------------- proc states
PROC: dict[str, int] = {
    "plc_proc_check_plasma": 10,
    "plc_proc_venting": 11,
    "plc_proc_start_power": 12,
    "plc_proc_cooling": 14,
    "plc_proc_plasma": 15,
    "plc_proc_wait_plasma": 18,
    "plc_proc_pierce": 27,
    "plc_proc_no_plasma": 62,
    "plc_proc_check_preflow": 16,
    "plc_proc_check_cutflow": 17,
    "plc_proc_check_gases": 23,
    "plc_proc_test_out": 24,
    "proc_m_function": 30,
    "proc_zeroing": 32,
    "plc_proc_probing": 33,
    "plc_proc_ignition": 50,
    "plc_proc_preheat": 51,
    "plc_proc_soft_start": 52,
    "plc_proc_piercing": 53,
    "plc_proc_flame": 54,
    "plc_proc_cutting": 60,
    "plc_proc_purge": 61,
    "plc_proc_no_cutting": 62,
    "plc_proc_moveup": 65,
    "plc_proc_spindle": 70,
    "plc_proc_idle": 0,
}

# --------------------------------------------------------------- exit codes
EXIT: dict[str, int] = {
    "plc_process": 0,
    "plc_exit_gas_fail": 2,
    "plc_exit_plasma_timeout": 3,
    "plc_exit_plasma_fail": 4,
    "plc_exit_alarm_key": 5,
    "plc_exit_coolant_fail": 6,
    "plc_exit_probe_error": 7,
    "plc_exit_motor_shorted": 8,
    "plc_exit_broadcast_error": 10,
    "plc_exit_normal": 99,
    "plc_exit_extern_break": 100,
}
EXIT_DESCRIPTIONS: dict[int, str] = {
    0: "PLC process is not finished yet",
    2: "PLC aborted, No air pressure sensor",
    3: "PLC aborted, No Arc sensor signal Timeout",
    4: "PLC aborted, PLC Plasma Start cutting procedure error",
    5: "PLC aborted, Emergency key pressed",
    6: "PLC aborted, No Coolant flow sensor",
    7: "PLC aborted, No signal from probe sensor",
    8: "PLC aborted, Motor short circuit detected (ET2/ET4 boards)",
    10: "Error send broadcast message in multi-device configuration",
    99: "Normal exit",
    100: "PLC procedure aborted from outside of PLC core",
}
EXIT_NORMAL = 99
EXIT_EXTERN_BREAK = 100

# ------------------------------------------------------ register addresses
GVAR_HW_INPUTS = [7180, 7181, 7182, 7183, 7188, 7189, 7190, 7191]
GVAR_HW_OUTPUTS = [7184, 7185, 7186, 7187, 7192, 7193, 7194, 7195]
GVAR_HW_ADC0 = 7196       # ADC0..7  = 7196..7203
GVAR_HW_DAC0 = 7270       # DAC0..7  = 7270..7277
GVAR_HW_PWM0 = 7278       # PWM0..7  = 7278..7285 (first table wins)
OUTPUT_STATE_BASE = 0x400  # gvarget(0x400 + n) is the state of output n
PRINT_FIRST, PRINT_LAST = 20000, 20100
MOTION_CODE = 6060         # GVAR_CURRENT_MOTION_CODE
MOTION_CODE_IDLE = 0x4D
MACHINE_POS_BASE = 5021    # 5021..5026 machine position X..C
PROGRAM_POS_BASE = 5041    # 5041..5046 program position X..C
PROGRAM_POS9_BASE = 17001  # 17001..17009 program position X..W
MACHINE_POS9_BASE = 17021  # 17021..17029 machine position X..W
DISABLE_HW_LIMITS = 5521
DISABLE_SW_LIMITS = 5525
FAST_G0MOVE = 5539         # accepted, changes nothing
G0PLC_SPEED = 8630
JOG_ACCEL_TIME = 8631      # GVAR_G0PLC_TIME
JOG_SPEED_UNITS = 8632     # GVAR_G0PLC_SPEED_UNITS
JOG_AXIS_SPEED = 8634      # GVAR_PLC_JOGSPEED_UNITS: (mask << 24) | speed
JOG = 8635                 # GVAR_PLC_JOG: bits 0..7 axes +, bits 8..15 axes -
SOFT_JOG_BASE = 100020     # software PLC: 100020 + axis jogs that axis
SOFT_START_HW = 100040     # software PLC: start hardware procedure M<N>
SOFT_START_EPARAM = 100041 # software PLC: its eparam

AXES = ("X", "Y", "Z", "A", "B", "C", "U", "V", "W")

GVAR: dict[str, int] = {}
for _i in range(8):
    GVAR[f"GVAR_HW_INPUTS{_i}"] = GVAR_HW_INPUTS[_i]
    GVAR[f"GVAR_HW_OUTPUTS{_i}"] = GVAR_HW_OUTPUTS[_i]
for _i in range(8):
    GVAR[f"GVAR_HW_ADC{_i}"] = GVAR_HW_ADC0 + _i
for _i in range(8):
    GVAR[f"GVAR_HW_DAC{_i}"] = GVAR_HW_DAC0 + _i
for _i in range(8):
    GVAR[f"GVAR_HW_PWM{_i}"] = GVAR_HW_PWM0 + _i
GVAR.update({
    "GVAR_THC0_CONTROL": 7570,
    "GVAR_THC1_CONTROL": 7575,
    "GVAR_CURRENT_MOTION_CODE": MOTION_CODE,
    "GVAR_MD_MASTER_MOTION_CODE": 7140,
    "GVAR_CURRENT_TOOL_NUMBER": 5400,
    "GVAR_CAMERA_READY": 7090,
    "GVAR_CURRENT_MACHINE_POSITION": MACHINE_POS_BASE,
    "GVAR_CURRENT_PROGRAM_POSITION": PROGRAM_POS_BASE,
    "GVAR_G0PLC_SPEED": G0PLC_SPEED,
    "GVAR_G0PLC_TIME": JOG_ACCEL_TIME,
    "GVAR_G0PLC_SPEED_UNITS": JOG_SPEED_UNITS,
    "GVAR_PLC_JOGSPEED_UNITS": JOG_AXIS_SPEED,
    "GVAR_PLC_JOG": JOG,
})

class _Names(dict):
    """The built-in names: a dict of the listed ones that also knows every
    ``PLS<k>_<FIELD>`` name (the softMC seed: "There is no limit of the number
    of ... PLSs", so they cannot all be listed; :func:`softmc.dynamic_name`)."""

    def __missing__(self, name):
        v = softmc.dynamic_name(name) if isinstance(name, str) else None
        if v is None:
            raise KeyError(name)
        return v

    def __contains__(self, name) -> bool:
        return dict.__contains__(self, name) or (
            isinstance(name, str) and softmc.dynamic_name(name) is not None)

    def get(self, name, default=None):
        try:
            return self[name]
        except KeyError:
            return default


class _Kinds(dict):
    """Which table each built-in name comes from (a PLS past the listed ones too)."""

    def get(self, name, default=None):
        v = dict.get(self, name)
        if v is None and isinstance(name, str) and softmc.dynamic_name(name) is not None:
            return "softMC register"
        return default if v is None else v


#: Every built-in name, available without any include, in table order.
BUILTIN_NAMES: dict[str, int] = _Names()
for _table in (PLCCMD, PLC_BROADCAST, PLC_MESSAGE, MAPPED_OUT, PROC, EXIT, GVAR, softmc.REGISTERS,
               softmc.CONSTANTS):
    for _name, _value in _table.items():
        BUILTIN_NAMES.setdefault(_name, _value)

#: Which table each built-in name comes from (for hover help and completion).
BUILTIN_KIND: dict[str, str] = _Kinds()
for _kind, _table in (("command", PLCCMD), ("broadcast", PLC_BROADCAST), ("message", PLC_MESSAGE),
                      ("mapped output", MAPPED_OUT), ("proc state", PROC), ("exit code", EXIT),
                      ("register", GVAR), ("softMC register", softmc.REGISTERS),
                      ("softMC constant", softmc.CONSTANTS)):
    for _name in _table:
        BUILTIN_KIND.setdefault(_name, _kind)


def _first_names(*tables: dict[str, int]) -> dict[int, str]:
    out: dict[int, str] = {}
    for t in tables:
        for name, value in t.items():
            out.setdefault(value, name)
    return out


_MESSAGE_NAMES = _first_names(PLCCMD, PLC_MESSAGE, PLC_BROADCAST)
_EXIT_NAMES = _first_names({k: v for k, v in EXIT.items() if k != "plc_process"})
_PROC_NAMES = _first_names({"plc_proc_idle": 0}, PROC)


def message_name(value: int) -> Optional[str]:
    """The name of a message code (PLCCMD_*, PLC_MESSAGE_*, PLC_BROADCAST_*), or None."""
    return _MESSAGE_NAMES.get(value)


def exit_name(code: int) -> Optional[str]:
    """The name of an exit code from the seed's table (99 is ``plc_exit_normal``), or None."""
    return _EXIT_NAMES.get(code)


def proc_name(value: int) -> Optional[str]:
    """The name of a ``proc`` state (0 is ``plc_proc_idle``), or None."""
    return _PROC_NAMES.get(value)


def describe_register(addr: int) -> Optional[str]:
    """What a gvarget/gvarset address is, in words, or None for a plain register."""
    for name, value in GVAR.items():
        if value == addr and not name.startswith("GVAR_CURRENT_MACHINE") \
                and not name.startswith("GVAR_CURRENT_PROGRAM"):
            extra = ""
            if addr == MOTION_CODE:
                extra = ": 0 while a PLC-commanded move or jog runs, 0x4d when motion is idle"
            elif addr == JOG:
                extra = ": jog, bits 0..7 axes moving +, bits 8..15 axes moving -, 0 stops"
            elif addr == JOG_AXIS_SPEED:
                extra = ": jog speed of the masked axes, (mask<<24)|speed"
            elif addr == JOG_ACCEL_TIME:
                extra = ": jog acceleration time in ms"
            return name + extra
    if OUTPUT_STATE_BASE <= addr < OUTPUT_STATE_BASE + 64:
        return f"state of output {addr - OUTPUT_STATE_BASE} (read-only)"
    if PRINT_FIRST <= addr <= PRINT_LAST:
        return "print: a value written here appears in the message log"
    if MACHINE_POS_BASE <= addr < MACHINE_POS_BASE + 6:
        return f"GVAR_CURRENT_MACHINE_POSITION {AXES[addr - MACHINE_POS_BASE]} (0.01 mm)"
    if PROGRAM_POS_BASE <= addr < PROGRAM_POS_BASE + 6:
        return f"GVAR_CURRENT_PROGRAM_POSITION {AXES[addr - PROGRAM_POS_BASE]} (0.01 mm)"
    if PROGRAM_POS9_BASE <= addr < PROGRAM_POS9_BASE + 9:
        return f"program position {AXES[addr - PROGRAM_POS9_BASE]} (0.01 mm / 0.01 deg)"
    if MACHINE_POS9_BASE <= addr < MACHINE_POS9_BASE + 9:
        return f"machine position {AXES[addr - MACHINE_POS9_BASE]} (0.01 mm / 0.01 deg)"
    if addr == DISABLE_HW_LIMITS:
        return "1 disables hardware limits"
    if addr == DISABLE_SW_LIMITS:
        return "1 disables software limits"
    if addr == FAST_G0MOVE:
        return "fast g0moveA implementation switch (accepted, changes nothing)"
    if SOFT_JOG_BASE <= addr < SOFT_JOG_BASE + 8:
        return f"software PLC: jog axis {AXES[addr - SOFT_JOG_BASE]} at this speed (0-X for negative)"
    if addr == SOFT_START_HW:
        return "software PLC: start hardware procedure M<value>"
    if addr == SOFT_START_EPARAM:
        return "software PLC: eparam for the next hardware procedure started via 100040"
    return softmc.describe(addr)


# ------------------------------------------------------ variables and slots
#: Predefined variables that live in the procedure's own variable slots.
#: The VM knows these slot numbers (eparam, message, proc, vexit, var00..15, Param).
SLOT_EPARAM = 0
SLOT_PROC = 1
SLOT_TIMER = 2
SLOT_VEXIT = 3
SLOT_MESSAGE = 4
SLOT_VAR00 = 5            # var00..var15 = slots 5..20
SLOT_PARAM = 21           # software procedures only
FIRST_USER_SLOT = 22      # user variables follow
MAX_USER_VARS = 32

SLOT_NAMES: dict[str, int] = {
    "eparam": SLOT_EPARAM,
    "proc": SLOT_PROC,
    "timer": SLOT_TIMER,
    "vexit": SLOT_VEXIT,
    "message": SLOT_MESSAGE,
    **{f"var{i:02d}": SLOT_VAR00 + i for i in range(16)},
    "command": SLOT_VAR00,
    "parameter": SLOT_VAR00 + 1,
}
SOFTWARE_SLOT_NAMES: dict[str, int] = {"Param": SLOT_PARAM}

#: Predefined variables mapped to hardware registers (read and written through them).
MAPPED_VARIABLES: dict[str, int] = {
    "pwm01": GVAR_HW_PWM0, "pwm02": GVAR_HW_PWM0 + 1, "pwm03": GVAR_HW_PWM0 + 2,
    "pwm04": GVAR_HW_PWM0 + 3,
    "dac01": GVAR_HW_DAC0, "dac02": GVAR_HW_DAC0 + 1,
    "adc01": GVAR_HW_ADC0, "adc02": GVAR_HW_ADC0 + 1,
}
READ_ONLY_VARIABLES = frozenset({"adc01", "adc02"})


def slot_name(slot: int, user_names: list[str] | tuple[str, ...] = ()) -> str:
    """The name of a variable slot (the canonical name for predefined ones)."""
    for name, s in SLOT_NAMES.items():
        if s == slot:
            return name
    if slot == SLOT_PARAM:
        return "Param"
    i = slot - FIRST_USER_SLOT
    if 0 <= i < len(user_names):
        return user_names[i]
    return f"v{slot}"


# --------------------------------------------------------- size limits
HW_PROC_LIMIT = 512
HW_TOTAL_LIMIT = 8192
SW_PROC_LIMIT = 16384
