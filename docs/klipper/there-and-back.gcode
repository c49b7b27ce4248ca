; one move along X and back: 2 x 10 mm x 80 steps/mm = 1,600 steps
SET_KINEMATIC_POSITION X=100 Y=100 Z=10
G1 X110 F6000
G1 X100
