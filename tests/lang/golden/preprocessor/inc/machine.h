// a project header with defines and a helper procedure
#define SPEED_SLOW 100
#define SPEED_FAST (SPEED_SLOW*5)

pause2()
{
    timer=2; do { timer--; } while (timer>0);
};
