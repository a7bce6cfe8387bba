// TG Motion target (docs/targets.md): the shared memory TGM_Data, 512 KiB,
// as 131072 32-bit words. Word i (bytes 4i .. 4i+3) is register TGM_DATA + i:
//     gvarset(TGM_DATA + 3, v);   v = gvarget(TGM_DATA + 3);
#define TGM_DATA        2000000
#define TGM_WORDS       131072   // how many (TGM_DATA + 0 .. TGM_DATA + TGM_WORDS - 1)

// The other shared memories of PLC_DATA, as far as the TG Motion manual
// documents them, mapped onto the simulated machine (docs/targets.md).
// TGM_System.HEADER: "The actual size of the shared memory is contained in the
// TGM_System.HEADER.Mem_Size_Data register" (read-only).
#define TGM_SYSTEM              2200000
#define HEADER_MEM_SIZE_DATA    2200000  // 524288: TGM_Data's size in bytes
#define HEADER_COMPATIBILITY_ID 2200001  // TG Motion's compatibility id
#define ID_COMPATIBILITY        4        // what a PLC for this TG Motion expects

// TGM_Servo: servo s (0 X, 1 Y, 2 Z ... the machine's axes), 100 registers each.
#define TGM_SERVO               2300000
#define SERVO_STRIDE            100
#define SERVO_ACT_POSITION      0        // + TGM_SERVO + s*SERVO_STRIDE: position, 0.01 mm
#define SERVO_STATUS            1        // bits below (read-only)
#define SERVO_DESIRED_POSITION  2        // write: the axis follows it, 0.01 mm
#define SERVO_ST_PRESENT        0x1
#define SERVO_ST_MOVING         0x2
#define SERVO_ST_IN_POSITION    0x4

// TGM_Dio: the I/O as 32-bit words, 8 of each.
#define TGM_DIO                 2400000
#define DIO_DI                  2400000  // + w: inputs 32w .. 32w+31 (read-only)
#define DIO_DO                  2400008  // + w: outputs 32w .. 32w+31
#define DIO_AI                  2400016  // + c: ADC channel c (read-only)
#define DIO_AO                  2400024  // + c: DAC channel c

// TGM_Oscilloscope: the samples taken after Program_04 of the signals picked.
#define TGM_OSC                 2500000  // the number of samples taken
#define OSC_LAST                2500001  // + k: signal k's last sample

// The diagnostic prints of PLC_DATA.functions: RtWprintf_String(v),
// RtWprintf_Long(v) and RtWprintf_Ex(severity, v) print v in the run log.
