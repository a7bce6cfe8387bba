// Huazhong target (docs/targets.md): the seed's system header, "#include plc.h".
//
// axis_stat(x) is the seed's macro F_ui[(x)*10]: the status word of axis x
// (0 X, 1 Y, 2 Z, 3 A ... as the machine has them), made by the CNC at every
// batch read. Its bits, as the seed defines them:
#define AX_SLSP         0x0001   // positive limit reached
#define AX_SLSN         0x0002   // negative limit reached
#define AX_HOME_LAMP    0x0004   // homing
#define AX_CMP_LAMP     0x0008   // backlash or pitch compensation (not modelled: 0)
#define AX_HOME_FIN     0x0010   // homing finished
#define AX_FSTOP_LAMP   0x0020   // stopped in position
#define AX_HOME_GOING   0x0040   // homing
#define AX_MOVING_LAMP  0x0080   // moving

// M, S, B and T functions: init() registers a handler with set_m_func(proc)
// (set_s_func, set_b_func, set_t_func); when the CNC issues the code, the
// handler is called and reads it here.
#define M_CODE          1009050  // the last M code issued (3 for M03)
#define S_CODE          1009051  // the last S value (1200 for S1200)
#define B_CODE          1009052
#define T_CODE          1009053
