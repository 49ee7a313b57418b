"""The simulators the tools run against: the test bench (bench/, DESIGN 7), richer than the control model,
for the identification and the HIL replay, and the 1->2 upshift driveline (plant/, DESIGN 10) for the shift
controller's closed loop."""
