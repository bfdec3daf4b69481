"""nbst.models: MuJoCo scenes generated from a problem and its solution, and
cross-validation of the analytic simulator against MuJoCo.

Installed as ``nbst.models`` (setuptools ``package-dir`` maps this folder).
Importing it does not import mujoco; the submodules that need it do.
"""
