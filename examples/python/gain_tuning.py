#!/usr/bin/python3
"""Sweeps the drive stiffness of the 7-dof arm (examples/arm7.urdf) and plots the RMS tracking
error of sine trajectories against stiffness, for PGS and TGS.

Every stiffness of the sweep is one copy of a featherdrive.Batch, so the sweep runs on all cores.
Each joint tracks 0.5 sin(2 pi 0.5 t + d) rad (d = the joint's index) with stiffness k and damping
2 sqrt(k * 0.05 kg m^2) on every joint, from the trajectory's start state, for --steps steps of
1/60 s; the error is the RMS over joints and steps of q - target.

usage: PYTHONPATH=build/python /usr/bin/python3 examples/python/gain_tuning.py [OUT.png]
       [--quick] [--steps N] [--urdf ROBOT.urdf]
"""
import argparse
import math
import os
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import featherdrive as fd  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
AMPLITUDE, FREQUENCY, INERTIA = 0.5, 0.5, 0.05


def trajectory(t, nv):
    """Target positions and velocities of every joint at time t."""
    phase = np.arange(nv, dtype=float)
    w = 2 * math.pi * FREQUENCY
    return AMPLITUDE * np.sin(w * t + phase), AMPLITUDE * w * np.cos(w * t + phase)


def sweep(model, solver, stiffness, steps, dt):
    """RMS tracking error for each stiffness, one batch copy per stiffness."""
    n, nv = len(stiffness), model.nv
    batch = fd.Batch(model, n, dt=dt, solver=solver, position_iterations=4, velocity_iterations=1)
    kp = np.repeat(np.asarray(stiffness, dtype=float)[:, None], nv, axis=1)
    batch.set_drive_gains(kp, 2.0 * np.sqrt(kp * INERTIA))
    q0, qd0 = trajectory(0.0, nv)
    batch.set_q(q0)
    batch.set_qd(qd0)
    squared = np.zeros(n)
    for k in range(steps):
        position, velocity = trajectory((k + 1) * dt, nv)  # targets at the step's end
        batch.set_drive_targets(position, velocity)
        batch.step()
        squared += np.mean((batch.q - position[None, :]) ** 2, axis=1)
    return np.sqrt(squared / steps)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", nargs="?", default="out/gain_tuning.png", help="the PNG to write")
    parser.add_argument("--quick", action="store_true", help="a short sweep (for the tests)")
    parser.add_argument("--steps", type=int, default=None, help="steps per run (default 240)")
    parser.add_argument("--urdf", default=str(ROOT / "examples" / "arm7.urdf"), help="the robot")
    args = parser.parse_args()

    model = fd.load_urdf(args.urdf).model
    dt = 1.0 / 60.0
    stiffness = np.logspace(1, 5, 4 if args.quick else 17)
    steps = args.steps if args.steps is not None else (30 if args.quick else 240)

    errors = {}
    print(f"{'stiffness':>12}  {'PGS rms error':>14}  {'TGS rms error':>14}")
    for solver in ("pgs", "tgs"):
        errors[solver] = sweep(model, solver, stiffness, steps, dt)
    for k, e_pgs, e_tgs in zip(stiffness, errors["pgs"], errors["tgs"]):
        print(f"{k:12.4g}  {e_pgs:14.6g}  {e_tgs:14.6g}")

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for solver, marker in (("pgs", "o"), ("tgs", "s")):
        ax.loglog(stiffness, errors[solver], marker=marker, label=solver.upper())
    ax.set_xlabel("drive stiffness [Nm/rad] (damping 2 sqrt(k 0.05 kg m$^2$))")
    ax.set_ylabel("RMS tracking error [rad]")
    ax.set_title(f"{pathlib.Path(args.urdf).name}: sine tracking, {steps} steps of 1/60 s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
