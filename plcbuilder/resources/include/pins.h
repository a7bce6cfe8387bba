// pins.h - the default pin map of PLC Builder's default machine
// (resources/machine/default.toml wires these inputs and outputs).
// Copy it into your project's include/ folder and edit it to match your board.
//
// Keep define names free of each other's full names: myCNC's own preprocessor
// substitutes substrings, so OUTPUT_SPINDLE and OUTPUT_SPINDLE_CCW cannot
// coexist on the controller (PLC Builder warns about such pairs).

// ---- inputs
#define INPUT_HOME_X        0   // X home switch, active 1 at X <= 0
#define INPUT_HOME_Y        1   // Y home switch, active 1 at Y <= 0
#define INPUT_HOME_Z        2   // Z home switch, active 1 at Z <= 0 (found by jogging Z-)
#define INPUT_PROBE         3   // touch probe, active 1 on the workpiece
#define INPUT_IHC           4   // plasma initial height control, reads 0 on contact
#define INPUT_ARC_OK        5   // plasma arc-OK, 1 a while after OUTPUT_PLASMA
#define INPUT_AIR_PRESSURE  6   // air pressure switch, 1 when pressure is good
#define INPUT_COOLANT_FLOW  7   // coolant flow switch, 1 when flood coolant flows
#define INPUT_ESTOP         8   // emergency stop button, 1 when pressed
#define INPUT_CYCLE_START   9   // a panel button
#define INPUT_LIMIT_MIN_X   10  // hard limit switches
#define INPUT_LIMIT_MAX_X   11
#define INPUT_LIMIT_MIN_Y   12
#define INPUT_LIMIT_MAX_Y   13
#define INPUT_LIMIT_MIN_Z   14
#define INPUT_LIMIT_MAX_Z   15

// ---- outputs
#define OUTPUT_SPINDLE      0   // spindle on (clockwise)
#define OUTPUT_CCW_SPINDLE  1   // spindle counter-clockwise
#define OUTPUT_MIST         2   // mist coolant
#define OUTPUT_FLOOD        3   // flood coolant
#define OUTPUT_PLASMA       4   // plasma torch on
#define OUTPUT_LUBE         5   // lubrication pump
#define OUTPUT_CHARGE_PUMP  6   // charge pump / watchdog
#define OUTPUT_ALARM_LAMP   7   // alarm lamp

// ---- PWM channels (pwm01 is PWM0)
#define PWM_SPINDLE_SPEED   0
