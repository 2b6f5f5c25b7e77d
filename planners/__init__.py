"""Motion planning for the IRB 140 cell: mink IK, ruckig trajectories, pick-and-place cycles.

The package knows MuJoCo models and poses, never tasks, tiles or rewards: functions take tool
poses, sets of equivalent yaws and belt velocities as numbers.
"""
