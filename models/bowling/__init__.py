"""nbst.models.bowling: ten-pin bowling synthesized on MuJoCo rollouts (docs/bowling.md).

Modules, one stage each: ``pin`` (the pin's profile, meshes and mass properties, trimesh),
``scene`` (the MjSpec scene, USBC dimensions), ``shot`` (throws, outcome, the rollout
runner), ``search`` (finding a throw for a set of pins), ``shotfile`` (the replayable shot
file). The machinery every rollout search shares (the runner, the archive, the noise and
probability, the robust maximiser, the ladder, the cluster hooks) is the rollout room's,
:mod:`nbst.models.mjsearch`. Importing this package imports neither mujoco nor trimesh.
"""
