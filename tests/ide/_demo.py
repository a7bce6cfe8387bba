"""A demo procedure that exercises every run panel: a move, outputs, PWM and DAC
ramps, messages, prints, and a wait on the cycle start button."""

DEMO_SOURCE = """\
#include pins.h
// A demo for the run panels: a move, outputs, PWM and DAC ramps,
// messages, prints, and a wait on the cycle start button.
main() {
  proc = plc_proc_moveup;
  portset(OUTPUT_CHARGE_PUMP);
  g0moveA(0x81, 1, 20000);          // X to 200 mm ...
  g0moveA(0x81, 2, 15000);          // ... and Y to 150 mm, together
  g0moveA(1, 3, 0);
  timer = 5; do { timer--; } while (timer > 0);
  do { motion = gvarget(6060); } while (motion != 0x4d);
  proc = plc_proc_spindle;
  portset(OUTPUT_SPINDLE);
  i = 0;
  do { i++; pwm01 = i * 4; dac01 = 3000 - i * 8; } while (i < 250);
  command = PLC_MESSAGE_SPINDLE_SPEED_CHANGED;   // tell myCNC the speed
  parameter = pwm01;
  message = PLCCMD_REPLY_TO_MYCNC;
  gvarset(20000, pwm01);
  portset(OUTPUT_MIST);
  g0moveA(1, 1, 5000);              // X back to 50 mm
  timer = 5; do { timer--; } while (timer > 0);
  do { motion = gvarget(6060); } while (motion != 0x4d);
  proc = plc_proc_check_plasma;
  portset(OUTPUT_ALARM_LAMP);
  do { button = portget(INPUT_CYCLE_START); } while (button == 0);
  portclear(OUTPUT_ALARM_LAMP);
  message = PLC_MESSAGE_PLASMA_OK;
  portclear(OUTPUT_MIST);
  i = 250;
  do { i--; pwm01 = i * 4; } while (i > 0);
  portclear(OUTPUT_SPINDLE);
  proc = plc_proc_idle;
  gvarset(20001, 7);
  exit(99);
}
"""
