"""The simulators the tools run against: the test bench (bench/, DESIGN 7), richer than the control model,
for the identification and the HIL replay, the 1->2 upshift driveline (plant/, DESIGN 10) for the shift
controller's closed loop, and the 8-speed vehicle (gearbox_plant/, DESIGN 15): engine, torque converter with its
lock-up clutch, every shift element its own true clutch, the gear sets' kinematics from a gearbox description,
driveline compliance and road load."""
