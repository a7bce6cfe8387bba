"""The machine description (TOML); the manual's examples of it and of plc-variables.xml."""

from __future__ import annotations

import re
import zipfile
from importlib import resources

import pytest

from plcbuilder.controller.machine_config import (
    ConfigError,
    MachineConfig,
    default_machine,
    default_machine_text,
    load_machine,
    parse_machine,
)
from plcbuilder.controller.variables_xml import parse_variables

GOOD = """\
name = "test"

[io]
inputs = 32
outputs = 16

[motion]
start_latency_ms = 3

[axes.X]
rapid = 6000
accel = 200.5
min = -5.0
max = 500
start = 10
offset = 2.5

[axes.A]

[[inputs]]
pin = 0
name = "HOME"
axis = "X"
below = 0.0

[[inputs]]
pin = 1
output = 2
delay_ms = 30

[[inputs]]
pin = 2
value = 1

[[adc]]
channel = 3
source = "ramp"
start = 0
end = 100
period_ms = 10
"""


def test_parse_good_file():
    """The machine being simulated is described by a file (axes: speeds,
    accelerations, limits; inputs tied to positions, such as home and limit
    switches and a probe; inputs tied to outputs with a delay, such as an arc-OK
    sensor; ADC sources)."""
    c = parse_machine(GOOD, "good.toml")
    assert c.name == "test" and c.input_count == 32 and c.output_count == 16
    assert c.start_latency_ms == 3
    assert list(c.axes) == ["X", "A"]
    x = c.axes["X"]
    assert (x.rapid, x.accel, x.soft_min, x.soft_max, x.start, x.offset) == \
        (6000.0, 200.5, -5.0, 500.0, 10.0, 2.5)
    assert c.axes["A"].rotary and not x.rotary
    kinds = [(i.pin, i.kind) for i in c.inputs]
    assert kinds == [(0, "axis"), (1, "output"), (2, "constant")]
    assert c.inputs[1].delay_ms == 30 and c.inputs[1].output == 2
    assert c.adc[0].source == "ramp" and c.adc[0].channel == 3
    assert c.source == "good.toml"


def test_empty_file_is_a_bare_board():
    c = parse_machine("")
    assert c.input_count == 64 and c.output_count == 64 and c.axes == {}
    assert c.start_latency_ms == 2 and c.jog_watchdog_ms == 1000
    assert MachineConfig().input_count == 64


def _err(text: str) -> ConfigError:
    with pytest.raises(ConfigError) as ei:
        parse_machine(text, "m.toml")
    return ei.value


def test_toml_syntax_error_names_file_and_line():
    """A bad machine file (TOML syntax) raises ConfigError naming file and line."""
    e = _err('name = "x"\n[axes.X]\nrapid = = 3\n')
    assert e.file == "m.toml" and e.line == 3
    assert str(e).startswith("m.toml:3: ") and "TOML syntax error" in str(e)


def test_unknown_key_names_file_line_and_key():
    """A bad machine file (unknown key) raises ConfigError naming file, line and key."""
    e = _err('[axes.X]\nrapid = 100\nspeeed = 3\n')
    assert (e.file, e.line, e.key) == ("m.toml", 3, "axes.X.speeed")
    assert "unknown key" in str(e) and str(e).startswith("m.toml:3: axes.X.speeed: ")


def test_unknown_top_level_key():
    e = _err('name = "a"\n\ncolour = "red"\n')
    assert (e.line, e.key) == (3, "colour")


def test_unknown_axis():
    e = _err('[axes.Q]\nrapid = 1\n')
    assert e.key == "axes.Q" and e.line == 1 and "unknown axis" in str(e)


def test_wrong_type_names_key_and_line():
    """A bad machine file (wrong type) raises ConfigError naming the key."""
    e = _err('[axes.X]\naccel = 100\nrapid = "fast"\n')
    assert (e.line, e.key) == (3, "axes.X.rapid") and "expected a number" in str(e)
    e = _err('[[inputs]]\npin = 1.5\nvalue = 1\n')
    assert (e.line, e.key) == (2, "inputs[0].pin") and "expected an integer" in str(e)
    e = _err('[[inputs]]\npin = true\nvalue = 1\n')
    assert "expected an integer" in str(e)


def test_out_of_range_pin():
    """A bad machine file (out-of-range pin) raises ConfigError naming the key and line."""
    text = '[io]\ninputs = 16\n\n[[inputs]]\npin = 3\nvalue = 1\n\n[[inputs]]\npin = 16\nvalue = 1\n'
    e = _err(text)
    assert (e.line, e.key) == (9, "inputs[1].pin") and "out of range" in str(e)
    e = _err('[[inputs]]\npin = 1\noutput = 64\n')
    assert e.key == "inputs[0].output" and e.line == 3
    e = _err('[[adc]]\nchannel = 8\n')
    assert e.key == "adc[0].channel"


def test_other_wiring_mistakes():
    assert "already wired" in str(_err('[[inputs]]\npin = 1\nvalue = 1\n[[inputs]]\npin = 1\nvalue = 0\n'))
    assert "exactly one" in str(_err('[[inputs]]\npin = 1\nvalue = 1\noutput = 2\n'))
    assert "not configured" in str(_err('[[inputs]]\npin = 1\naxis = "Y"\nbelow = 0\n'))
    assert "below" in str(_err('[axes.X]\n[[inputs]]\npin = 1\naxis = "X"\n'))
    assert "min" in str(_err('[axes.X]\nmin = 10\nmax = 5\n'))
    assert "greater than 0" in str(_err('[axes.X]\nrapid = 0\n'))
    assert "hard_limit" in _err('[[inputs]]\npin = 1\nvalue = 1\nhard_limit = true\n').key
    assert "not used" in str(_err('[[adc]]\nchannel = 0\nsource = "constant"\naxis = "X"\n'))
    assert "not one of" in str(_err('[[adc]]\nchannel = 0\nsource = "sine"\n'))
    assert "array of tables" in str(_err('inputs = 3\n'))


def test_load_machine_names_the_file(tmp_path):
    p = tmp_path / "mach.toml"
    p.write_text('[axes.X]\nrapid = -1\n', encoding="utf-8")
    with pytest.raises(ConfigError) as ei:
        load_machine(p)
    assert str(ei.value).startswith(f"{p}:2: axes.X.rapid: ")
    with pytest.raises(ConfigError) as ei:
        load_machine(tmp_path / "missing.toml")
    assert "missing.toml" in str(ei.value)
    p.write_text(GOOD, encoding="utf-8")
    assert load_machine(p).source == str(p)


def test_default_machine_is_package_data():
    """Projects get a sensible default machine (package data, read through
    importlib.resources so that it works from an installed wheel)."""
    c = default_machine()
    assert set(c.axes) == {"X", "Y", "Z"}
    assert default_machine() is c
    text = resources.files("plcbuilder").joinpath("resources/machine/default.toml").read_text()
    assert text == default_machine_text()


def test_default_machine_is_in_the_wheel_package_data():
    """resources/ is package data: it works from an installed wheel."""
    import tomllib
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    cfg = tomllib.loads((root / "pyproject.toml").read_text())
    patterns = cfg["tool"]["setuptools"]["package-data"]["plcbuilder"]
    assert any(Path("resources/machine/default.toml").match(p.replace("**/", "*/"))
               or p == "resources/**/*" for p in patterns)


def _pins_h() -> dict[str, int]:
    text = resources.files("plcbuilder").joinpath("resources/include/pins.h").read_text()
    return {m.group(1): int(m.group(2), 0)
            for m in re.finditer(r"^#define\s+(\w+)\s+(\w+)", text, re.M)}


def test_default_machine_wiring_matches_pins_h():
    """Projects get a sensible default machine, and the built-in headers include a
    default pins.h whose names (INPUT_HOME_X, INPUT_HOME_Y, INPUT_HOME_Z,
    INPUT_PROBE, INPUT_IHC, OUTPUT_SPINDLE, OUTPUT_MIST, OUTPUT_PLASMA, …) match
    the default machine's wiring."""
    pins = _pins_h()
    c = default_machine()
    ins = c.input_names()
    outs = c.output_names()
    for name, pin in pins.items():
        if name.startswith("INPUT_"):
            assert ins.get(pin) == name, name
        elif name.startswith("OUTPUT_"):
            assert outs.get(pin) == name, name
    assert set(ins.values()) == {n for n in pins if n.startswith("INPUT_")}
    assert set(outs.values()) == {n for n in pins if n.startswith("OUTPUT_")}
    plasma = pins["OUTPUT_PLASMA"]
    arc = next(i for i in c.inputs if i.name == "INPUT_ARC_OK")
    assert arc.kind == "output" and arc.output == plasma and arc.delay_ms > 0
    flow = next(i for i in c.inputs if i.name == "INPUT_COOLANT_FLOW")
    assert flow.output == pins["OUTPUT_FLOOD"]


def test_default_machine_loads_from_a_zip_import(tmp_path, monkeypatch):
    """The default machine is read through importlib.resources, so it also loads
    from a zipped (wheel-like) install, not only from a checkout."""
    import importlib
    import sys
    from pathlib import Path
    pkg = Path(__file__).resolve().parents[2] / "plcbuilder"
    z = tmp_path / "plcb.zip"
    with zipfile.ZipFile(z, "w") as zf:
        for f in pkg.rglob("*"):
            if f.is_file() and "__pycache__" not in f.parts:
                zf.write(f, "plcbuilder/" + f.relative_to(pkg).as_posix())
    saved = {k: v for k, v in sys.modules.items() if k == "plcbuilder" or k.startswith("plcbuilder.")}
    for k in saved:
        del sys.modules[k]
    monkeypatch.syspath_prepend(str(z))
    try:
        cfgmod = importlib.import_module("plcbuilder.controller.machine_config")
        assert ".zip" in cfgmod.__file__
        c = cfgmod.default_machine()
        assert set(c.axes) == {"X", "Y", "Z"}
    finally:
        for k in [k for k in sys.modules if k == "plcbuilder" or k.startswith("plcbuilder.")]:
            del sys.modules[k]
        sys.modules.update(saved)


def test_docs_examples_parse():
    """The machine file and plc-variables.xml examples in docs/machine.md are valid."""
    from pathlib import Path
    doc = Path(__file__).resolve().parents[2] / "docs" / "machine.md"
    text = doc.read_text(encoding="utf-8")
    toml_blocks = [b for b in re.findall(r"```toml\n(.*?)```", text, re.S) if "[axes." in b]
    xml_blocks = [b for b in re.findall(r"```xml\n(.*?)```", text, re.S) if "<plc-variables" in b]
    assert toml_blocks and xml_blocks
    c = parse_machine(toml_blocks[0], "docs")
    assert c.axes["X"].offset == 10.0 and len(c.adc) == 3
    v = parse_variables(xml_blocks[-1], "docs")   # the format chapter's example
    assert v[:4] == [5, -20, 0, 16] and v[15] == -1
    with pytest.raises(ConfigError) as ei:
        parse_variables('<plc-variables>\n\n\n<var name="var16" value="1"/>\n</plc-variables>',
                        "plc-variables.xml")
    assert str(ei.value) == "plc-variables.xml:4: var16: unknown variable 'var16' (var00..var15)"


@pytest.mark.parametrize("key", ["accel", "rapid"])
def test_physical_bounds_of_an_axis(key):
    # issue 17 item 7: 5e-324 passed validation and divided by zero in motion.trapezoid
    e = _err(f'name = "m"\n[axes.Z]\n{key} = 5e-324\n')
    unit = "mm/min" if key == "rapid" else "mm/s²"
    assert (e.file, e.line, e.key) == ("m.toml", 3, f"axes.Z.{key}")
    assert f"out of range (allowed: 0.01 to 10000000 {unit})" in str(e)
    assert str(e).startswith(f"m.toml:3: axes.Z.{key}: 5e-324")
    e = _err(f'[axes.X]\n{key} = 1e9\n')
    assert "allowed: 0.01 to 10000000" in str(e)
    parse_machine(f'[axes.X]\n{key} = 0.01\n')                 # the bounds are allowed
    e = _err('[axes.X]\njog = -1\n')
    assert "allowed: 0 to 10000000 mm/min" in str(e)
