"""Is a built-in's bounce resolved by its step? One contact of bank-shot and two of billiards, each
started at 11 points spread over a few steps of flight (so that the contact begins at every phase of
a step), no gravity, at a ladder of steps: the mean and the range of what comes out, and how long
the contact pushes (``nbst.scene.contacts.contact_time``). A bounce the step does not resolve
changes with where in a step it begins. Prints; asserts nothing (the tests hold the shipped steps).

    python benchmarks/bench_scene_bounce.py
"""
from __future__ import annotations

import mujoco
import numpy as np

from nbst.scene.contacts import contact_time
from nbst.scene.scenefile import load_fates

STEPS_MS = (2.0, 1.0, 0.5, 0.25, 0.0625)


def phases(model, setup, read, h: float, span: float, t: float, n: int = 11) -> np.ndarray:
    """``read(data)`` after ``t`` s from ``n`` starts whose contact begins at points spread over ``span``
    s (``setup(data, lead)`` places the bodies ``lead`` s of flight further back), no gravity, step
    ``h`` (the model's step and gravity are changed). tests/test_scene_contact_time.py uses it too."""
    model.opt.timestep, model.opt.gravity[:] = h, 0.0
    out = []
    for lead in np.linspace(0.0, span, n):
        d = mujoco.MjData(model)
        setup(d, lead)
        for _ in range(int(round(t / h))):
            mujoco.mj_step(model, d)
        out.append(read(d))
    return np.array(out)


def board_bounce(m):
    """bank-shot: the ball square on to the backboard at 4 m/s, 5 rad/s of back spin: (setup, read the
    speed off it (m/s), span, t)."""
    j = m.body("ball").jntadr[0]
    qa, va = m.jnt_qposadr[j], m.jnt_dofadr[j]

    def setup(d, lead):
        d.qpos[qa:qa + 3] = [2.24 - 0.06 - 0.05 - 4.0 * lead, 0.0, 1.85]
        d.qvel[va:va + 6] = [4.0, 0, 0, 0, 5.0, 0]

    return setup, lambda d: -float(d.qvel[va]), 0.004, 0.05


def _cue_and_3(m):
    c, b = m.body("cue").jntadr[0], m.body("ball3").jntadr[0]
    return m.jnt_qposadr[c], m.jnt_qposadr[b], m.jnt_dofadr[c], m.jnt_dofadr[b]


def ball_on_ball(m):
    """billiards: the cue at 2 m/s head on into the 3, in the air: (setup, read the restitution, span, t)."""
    qc, q3, vc, v3 = _cue_and_3(m)

    def setup(d, lead):
        d.qpos[q3:q3 + 3] = [0.0, 0.0, 0.5]
        d.qpos[qc:qc + 3] = [-0.0572 - 0.01 - 2.0 * lead, 0.0, 0.5]
        d.qvel[vc] = 2.0

    return setup, lambda d: float(d.qvel[v3] - d.qvel[vc]) / 2.0, 0.002, 0.03


def ball_on_cushion(m):
    """billiards: the cue at 2 m/s square into the east cushion, at its height: (setup, read the
    restitution, span, t)."""
    qc, q3, vc, _ = _cue_and_3(m)

    def setup(d, lead):
        d.qpos[q3:q3 + 3] = [0.0, -0.3, 0.5]
        d.qpos[qc:qc + 3] = [1.27 - 0.0286 - 0.01 - 2.0 * lead, 0.3, 0.018]
        d.qvel[vc] = 2.0

    return setup, lambda d: -float(d.qvel[vc]) / 2.0, 0.002, 0.03


def _row(label: str, model, case, tau: float, zeta: float) -> None:
    setup, read, span, t = case
    print(f"\n{label} (solref {tau:g} {zeta:g}: pushes {contact_time(tau, zeta, 0.0) * 1e3:.2f} ms)")
    print("| step (ms) | steps in the contact | mean | range over 11 phases |")
    print("|---|---|---|---|")
    for ms in STEPS_MS:
        h = ms / 1e3
        v = phases(model, setup, read, h, span, t)
        print(f"| {ms:g} | {contact_time(tau, zeta, h) / h:.1f} | {v.mean():.3f} | {v.min():.3f}-{v.max():.3f} |")


def main() -> None:
    print(f"# bounces against the step, MuJoCo {mujoco.__version__}")
    _, m = load_fates("bank-shot")
    print(f"bank-shot's step: {m.opt.timestep * 1e3:g} ms")
    _row("bank-shot: the ball square on to the backboard at 4 m/s, 5 rad/s of back spin; speed off it (m/s)",
         m, board_bounce(m), *m.geom_solref[m.geom("ball_g").id])
    _, m = load_fates("billiards")
    print(f"\nbilliards' step (its fates file): {m.opt.timestep * 1e3:g} ms")
    _row("billiards: the cue at 2 m/s head on into the 3, in the air; restitution", m, ball_on_ball(m),
         *m.geom_solref[m.geom("cue_g").id])
    _row("billiards: the cue at 2 m/s square into the east cushion, at the cushion's height; restitution", m,
         ball_on_cushion(m), *m.geom_solref[m.geom("cushion_e").id])


if __name__ == "__main__":
    main()
