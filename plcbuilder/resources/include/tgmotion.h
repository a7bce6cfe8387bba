// TG Motion target (docs/targets.md): the shared memory TGM_Data, 512 KiB,
// as 131072 32-bit words. Word i (bytes 4i .. 4i+3) is register TGM_DATA + i:
//     gvarset(TGM_DATA + 3, v);   v = gvarget(TGM_DATA + 3);
#define TGM_DATA        2000000
#define TGM_WORDS       131072   // how many (TGM_DATA + 0 .. TGM_DATA + TGM_WORDS - 1)
