"""nbst.models.bowling: ten-pin bowling synthesized on MuJoCo rollouts (docs/bowling.md).

Modules, one stage each: ``pin`` (the pin's profile, meshes and mass properties, trimesh),
``scene`` (the MjSpec scene, USBC dimensions), ``shot`` (throws, outcome, the rollout
runner), ``search`` (finding a throw for a set of pins), ``shotfile`` (the replayable shot
file), ``cli`` (``nbst bowl``). Importing this package imports neither mujoco nor trimesh.
"""
