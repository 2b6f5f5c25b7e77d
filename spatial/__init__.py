"""Facts of space and units shared by qshape, planners and envs (a library below all three).

- `spatial.angles`: planar angle wrapping (both conventions at the edge), 2D rotation, and the
  yaw error modulo a rotational symmetry, the symmetry period and the equivalent yaws.
- `spatial.rotations`: yaw about world z from a quaternion or a rotation matrix, and the
  quaternion of a yaw.
- `spatial.tolerance`: the placement tolerance (1.5 mm / 2 deg) and a made tile's deviation.
- `spatial.units`: millimetres per metre (designs are in mm, the world in m).

It imports numpy only: `qshape` (no MuJoCo) and `planners` (no shapes) may both depend on it.
"""
