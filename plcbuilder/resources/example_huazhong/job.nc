(A Huazhong job: plcbuilder run . --gcode job.nc --ms 15000; M and S go to on_m and on_s)
G28 X0              (home X: the "X homed" lamp Y0.5 comes on)
S1500 M03           (on_s, then on_m: spindle on)
M08
G1 X50 F3000        (the "X moving" lamp Y0.6 while it moves)
M09
M05
M30
