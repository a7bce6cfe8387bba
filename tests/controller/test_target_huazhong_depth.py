"""Seed 001 in depth (issue 27, items 5-7): the typed register views, axis_stat
and the AX_* bits fed from the machine, and the M/S/B/T function handlers that
init() registers. Each test quotes the seed's sentence (translated; the
Chinese original in the docstring where it is short) it implements."""

from __future__ import annotations

import pytest

from plcbuilder.api import CompileOptions, compile_source
from plcbuilder.bytecode import targets as T
from plcbuilder.controller.events import Note
from tests.controller._targets import controller, faults

HEAD = "#include plc.h\n"


def _hz(plc1: str, init: str = "", rest: str = "", **config):
    c = controller(HEAD + f"init() {{ plc1_time = 1; {init} }}\nplc1() {{ {plc1} }}\n"
                   f"plc2() {{ }}\n{rest}", "huazhong", **config)
    return c


def test_r_views_alias_the_same_768_bytes():
    """The seed: "以下外部变量声明都指向同一块内存,即PLC中间寄存器R,共有768个字节"
    (these declarations all point to the same memory, the PLC's internal
    registers R, 768 bytes): R_uc, R_c, R_ui, R_i, R_ul, R_l. Borland C++ 3.1:
    int is 16 bits, long 32, x86 byte order."""
    c = _hz("""
        R_ui[0] = 0x1234;   a = R[0];  b = R[1];
        R_c[2] = 0-1;       c1 = R[2]; c2 = R_c[2]; c3 = R_uc[2];
        R_ul[1] = 0x12345678; d1 = R[4]; d2 = R[7]; d3 = R_ui[2]; d4 = R_ui[3];
        R_i[5] = 0-2;       e1 = R_ui[5]; e2 = R_i[5]; e3 = R_l[2];
        R_l[191] = 0-1;     f1 = R[767]; f2 = R_ul[191];
        i = 3; R_ui[i] = 0xabcd; g = R[7];
    """)
    c.step(1)
    assert faults(c) == []
    v = c.variables()["plc"]
    assert (v["a"], v["b"]) == (0x34, 0x12)
    assert (v["c1"], v["c2"], v["c3"]) == (255, -1, 255)
    assert (v["d1"], v["d2"], v["d3"], v["d4"]) == (0x78, 0x12, 0x5678, 0x1234)
    # R_l[2] is bytes 8..11: R_ui[4] = 0 below, R_i[5] = 0xfffe above: 0xfffe0000
    assert (v["e1"], v["e2"], v["e3"]) == (0xFFFE, -2, 0xFFFE0000 - (1 << 32))
    assert (v["f1"], v["f2"]) == (255, -1)      # unsigned long 0xffffffff: the same 32 bits
    assert v["g"] == 0xab


@pytest.mark.parametrize("bank,size", [("R_uc", 768), ("R_c", 768), ("R_ui", 384), ("R_i", 384),
                                       ("R_ul", 192), ("R_l", 192), ("X_ui", 64), ("Y_ul", 32),
                                       ("F_uc", 512), ("F_ui", 256), ("G_l", 128), ("P_uc", 200),
                                       ("B_ul", 50)])
def test_views_have_the_seeds_widths(bank, size):
    """The seed: "_uc表示以无符号字符型存取PLC寄存器 … _l代表以长整型存取PLC寄存器"
    (_uc: as unsigned char, _c: char, _ui: unsigned, _i: int, _ul: unsigned
    long, _l: long), over X, Y, F, G, P, B as over R; with the seed's 16-bit
    compiler (Borland C++ 3.1) int is 2 bytes and long 4."""
    assert T.BANKS[bank].size == size
    ok = compile_source(f"init(){{ a = {bank}[{size - 1}]; }}\nplc1(){{}}\nplc2(){{}}",
                        "plc.plc", CompileOptions(target="huazhong"))
    assert ok.ok
    bad = compile_source(f"init(){{ a = {bank}[{size}]; }}\nplc1(){{}}\nplc2(){{}}",
                         "plc.plc", CompileOptions(target="huazhong"))
    assert any(d.code == "index-range" for d in bad.diagnostics)


def test_views_of_x_f_p_and_b():
    """"同理,和R寄存器一样,系统提供如下变量定义供用户灵活使用" (likewise, as for R,
    the system provides these for X, Y, F, G, P, B): X_ui[0] is inputs 0..15,
    F_uc the bytes of F, P_ul two parameters, B_i a kept word as signed."""
    c = _hz("x = X_ui[0]; f = F_uc[3]; p = P_ul[0]; B_i[3] = 0-5; b = B[3]; y = Y_ui[0];"
            "Y_ui[0] = 0x8001;", parameters=(0x1111, 0x2222))
    c.set_input(0, 1)
    c.set_input(9, 1)
    c.machine.gvarset(T.CNC_F_BASE + 1, 0xAB00)      # the CNC's F[1] (F[0] is axis_stat(0))
    c.step(2)
    v = c.variables()["plc"]
    assert v["x"] == 0x0251          # inputs 0 and 9, and the default machine's 4 and 6
    assert v["p"] == 0x22221111 and v["f"] == 0xAB
    assert v["b"] == 0xFFFB and c.retained()[3] == 0xFFFB
    assert c.machine.outputs_on() == [0, 15]         # Y_ui[0] = 0x8001: Y0.0 and Y1.7


def test_a_write_to_a_signed_view_warns_with_the_value_stored():
    """a write keeps the element's width: R_c[0] = 200; stores -56 (a char)."""
    r = compile_source("init(){ R_c[0] = 200; }\nplc1(){}\nplc2(){}", "plc.plc",
                       CompileOptions(target="huazhong"))
    w = [d for d in r.diagnostics if d.code == "element-width"]
    assert w and "stores -56" in w[0].message


# ------------------------------------------------------------------ axis_stat
def test_axis_stat_is_f_ui_x_times_10_with_the_seeds_bits():
    """The seed: "#define axis_stat(x) (F_ui[(x)*10]) //轴状态字,共16位(bit)" (the axis
    status word, 16 bits), with AX_MOVING_LAMP "轴正在移动" (moving) and
    AX_FSTOP_LAMP "轴已精确定位停止" (stopped in position), fed from the machine's
    axes at every batch read."""
    c = _hz("s = axis_stat(0); f = F_ui[0]; z = axis_stat(2);"
            "if (axis_stat(0) & AX_MOVING_LAMP) moving++;",
            init="g0moveA(3, 1, 20000);")
    c.step(1)
    v = c.variables()["plc"]
    assert v["s"] == v["f"] and v["s"] & 0x20 and not v["s"] & 0x80
    c.step(50)
    v = c.variables()["plc"]
    assert v["s"] & 0x80 and not v["s"] & 0x20 and v["moving"] > 40
    assert v["z"] == 0x20                           # Z stands still
    c.step(3000)
    assert c.variables()["plc"]["s"] & 0xFF == 0x20


def test_axis_stat_limits():
    """AX_SLSP "轴正极限到" and AX_SLSN "轴负极限到" (positive / negative limit
    reached): the axis at its soft limit, or a hard-limit switch active."""
    c = _hz("s = axis_stat(0);", init="g0moveA(3, 1, 0-1000);")
    c.step(2000)
    assert c.machine.axis_positions()["X"] == -1000          # the soft minimum, -10 mm
    assert c.variables()["plc"]["s"] & 0x3 == T.AX_BITS["AX_SLSN"]
    c.set_input(11, 1)                                      # INPUT_LIMIT_MAX_X by hand
    c.step(2)
    assert c.variables()["plc"]["s"] & 0x3 == 0x3


def test_axis_stat_homing_and_home_finished():
    """AX_HOME_LAMP / AX_HOME_GOING "轴正在回零" (homing) while the CNC homes the
    axis, then AX_HOME_FIN "回零结束" (homing finished): a program that waits
    for it works against the machine model."""
    c = _hz("s = axis_stat(0); if (axis_stat(0) & AX_HOME_FIN) Y[0] |= 0x01;")
    c.step(2)
    assert not c.variables()["plc"]["s"] & 0x10
    home = c.machine.home_position(0)
    assert home == 0.0
    c.machine.motion.line_to({0: home}, feed=1000.0, homing=(0,))
    c.machine.quiet = False
    c.step(10)
    assert c.variables()["plc"]["s"] & 0x44 == 0x44 and c.machine.outputs_on() == []
    c.step(7000)
    assert c.variables()["plc"]["s"] & 0x10 and c.machine.outputs_on() == [0]


# ------------------------------------------------------------------ handlers
HANDLERS = """
onm() { m = gvarget(M_CODE); if (m == 3) Y[0] |= 0x01; if (m == 5) Y[0] &= ~0x01; n++; }
ons() { s = gvarget(S_CODE); G[5] = s; }
"""


def test_init_registers_the_m_and_s_handlers():
    """The seed: "函数init()是用户PLC程序的初始化函数,系统将只在初始化时调用该函数一次。
    该函数一般设置系统MSBT功能的响应函数" (init() ... generally sets up the response
    functions of the system's M, S, B, T functions): set_m_func(onm) in init();
    the CNC's M3 then calls onm(), which reads the code at M_CODE."""
    c = _hz("", init="set_m_func(onm); set_s_func(ons);", rest=HANDLERS)
    c.step(2)
    c.plc.issue_function("S", 1200)
    c.plc.issue_function("M", 3)
    c.step(1)
    assert c.machine.outputs_on() == [0]
    assert c.machine.gvarget(T.CNC_G_BASE + 5) == 1200
    c.plc.issue_function("M", 5)
    c.step(1)
    assert c.machine.outputs_on() == [] and c.variables()["plc"]["n"] == 2
    rep = c.target_report()
    assert rep["handlers"] == {"M": "onm", "S": "ons"} and rep["calls"]["onm"] == 2


def test_a_code_without_a_handler_is_a_warning():
    c = _hz("")
    c.step(1)
    c.plc.issue_function("T", 4)
    c.step(1)
    notes = [e.text for e in c.drain_events() if isinstance(e, Note)]
    assert any("T4: no T function handler is registered" in t for t in notes)


def test_a_handler_must_be_a_procedure_of_the_program():
    r = compile_source(HEAD + "init(){ set_m_func(nothing); }\nplc1(){}\nplc2(){}", "plc.plc",
                       CompileOptions(target="huazhong"))
    assert [d.code for d in r.diagnostics if d.is_error] == ["handler"]
    r = compile_source(HEAD + "init(){ set_m_func(onm); }\nplc1(){}\nplc2(){}\nonm(){ }",
                       "plc.plc", CompileOptions(target="huazhong"))
    assert r.ok and "onm" in dict(r.program.procs)         # a handler is compiled in


def test_a_g_code_job_calls_the_handlers_and_g28_homes():
    """Item 7: the handlers are "called when the simulated CNC issues that code
    (from a scenario, the IDE, or the G-code job)", and item 6: "a Huazhong
    program that waits for AX_HOME_FIN works against the machine model": G28 X0
    homes X (to its home switch), the job goes on when each handler returned."""
    c = _hz("if (axis_stat(0) & AX_HOME_FIN) Y[0] |= 0x02;",
            init="set_m_func(onm); set_s_func(ons);", rest=HANDLERS)
    c.job_open("G28 X0\nS900 M03\nG0 X50\nM05\nM30\n", "job.nc", play=True)
    c.step(200)
    assert 1 not in c.machine.outputs_on()
    c.run_until_idle(20_000)
    rep = c.job_report()
    assert rep["state"] == "ended" and faults(c) == []
    assert [(m["code"], m["procedure"], m["exit_code"]) for m in rep["mcodes"]] == \
        [("S900", "ons", 0), ("M03", "onm", 0), ("M05", "onm", 0)]
    assert c.machine.axis_positions()["X"] == 5000
    assert 1 in c.machine.outputs_on()                # homed: Y0.1 on
    assert c.machine.gvarget(T.CNC_G_BASE + 5) == 900


def test_a_scenario_code_line_calls_a_handler():
    """Item 7: "called when the simulated CNC issues that code (from a
    scenario ...)": ``code M3 @ 10``."""
    from plcbuilder.controller.scenario import Scenario, drive
    c = _hz("", init="set_m_func(onm);", rest=HANDLERS)
    drive(c, Scenario.parse("code M3 @ 10\ncode M5 @ 20\n"), 30)
    assert c.variables()["plc"]["n"] == 2 and c.machine.outputs_on() == []
    assert "code M3 @ 10" in c.recorder.text(30)


def test_g28_needs_a_home_switch():
    """Bad input: G28 of an axis without a home switch is refused naming the line."""
    from plcbuilder.controller.controller import Controller, ControllerError
    from plcbuilder.controller.machine_config import parse_machine
    from plcbuilder.controller.targets import TargetConfig
    from tests.controller._targets import compiled
    c = Controller(parse_machine("[axes.X]\n[axes.Z]\n", "m.toml"),
                   target=TargetConfig("huazhong"))
    c.load([compiled("init(){}\nplc1(){}\nplc2(){}", "huazhong")])
    with pytest.raises(ControllerError, match=r"job\.nc:2: G28: axis Z has no home switch"):
        c.job_open("G0 X1\nG28 Z0\n", "job.nc")
    with pytest.raises(ControllerError, match=r"job\.nc:1: G28: no axis"):
        c.job_open("G28\n", "job.nc")
