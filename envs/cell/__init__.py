"""The simulated MuJoCo cell: robot, belts, mesh, cameras, suction and tiles.

Below the Gymnasium task (``envs``): it knows tiles and slots as bodies and poses, never
rewards, observations or action spaces.
"""
