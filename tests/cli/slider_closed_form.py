#!/usr/bin/python3
"""`featherdrive simulate` on a one-dof slider scene reproduces, row by row, the implicit-Euler
recurrence that a PGS drive step solves exactly for one dof:

  m (v1 - v0) = dt s (kp (xT - x0 - dt v1) + kd (vT - v1)) + dt F,   x1 = x0 + dt v1,
  f = s (kp (xT - x0 - dt v1) + kd (vT - v1)),

with s = 1 for a force drive and s = m for an acceleration drive, F = m g along the axis, and
sine targets taken at each step's end time (k + 1) dt. Row k's target and target_velocity
columns are the command of the step from row k to row k + 1 (fit reads them so): the targets at
(k + 1) dt. The scene parameters are copied here from the files by hand.

usage: slider_closed_form.py FEATHERDRIVE SCENE OUT_DIR
"""
import csv
import math
import os
import subprocess
import sys

M = 2.5  # examples/slider.urdf: <mass value="2.5"/>, axis z, no <dynamics>

SCENES = {
    "slider.yaml": dict(g_axis=-9.81, dt=0.016666666666666666, steps=240, accel=False, kp=400.0,
                        kd=40.0, x0=0.05, v0=0.0, sine=(0.2, 0.5, 0.3, 0.1)),
    "slider_constant.yaml": dict(g_axis=0.0, dt=0.016666666666666666, steps=200, accel=False,
                                 kp=400.0, kd=20.0, x0=0.0, v0=0.0, constant=(0.3, 0.1)),
    "slider_acceleration.json": dict(g_axis=-9.81, dt=0.01, steps=300, accel=True, kp=100.0,
                                     kd=20.0, x0=-0.2, v0=0.5, sine=(0.3, 1.5, -0.4, 0.0)),
}


def target(p, t):
    if "constant" in p:
        return p["constant"]
    a, f, phase, offset = p["sine"]
    w = 2 * math.pi * f
    return offset + a * math.sin(w * t + phase), a * w * math.cos(w * t + phase)


def main():
    cli, scene, out_dir = sys.argv[1:4]
    name = os.path.basename(scene)
    p = SCENES[name]
    os.makedirs(out_dir, exist_ok=True)
    out = os.path.join(out_dir, name + ".csv")
    run = subprocess.run([cli, "simulate", scene, "--out", out], capture_output=True, text=True,
                         timeout=120)
    if run.returncode != 0:
        sys.exit(f"featherdrive failed ({run.returncode}): {run.stderr}")
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header = ",".join(rows[0])
    if header != "step,t,q:slide,qd:slide,f:slide,target:slide,target_velocity:slide":
        sys.exit(f"FAIL: header {header!r}")
    data = rows[1:]
    if len(data) != p["steps"] + 1:
        sys.exit(f"FAIL: {len(data)} rows, expected {p['steps'] + 1}")

    dt, kp, kd = p["dt"], p["kp"], p["kd"]
    s = M if p["accel"] else 1.0
    F = M * p["g_axis"]
    x, v, f = p["x0"], p["v0"], 0.0
    worst = 0.0
    for k, row in enumerate(data):
        if k > 0:
            xT, vT = target(p, k * dt)  # step k - 1 ends at t = k dt
            v1 = (M * v + dt * s * (kp * (xT - x) + kd * vT) + dt * F) / (M + s * (dt * dt * kp + dt * kd))
            f = s * (kp * (xT - x - dt * v1) + kd * (vT - v1))
            x, v = x + dt * v1, v1
        step, t, q, qd, force = int(row[0]), float(row[1]), float(row[2]), float(row[3]), float(row[4])
        command = target(p, (k + 1) * dt)
        checks = [("step", step, k, 0), ("t", t, k * dt, 1e-12), ("q", q, x, 1e-12),
                  ("qd", qd, v, 1e-12), ("f", force, f, 1e-12 * max(1.0, abs(f))),
                  ("target", float(row[5]), command[0], 1e-12),
                  ("target_velocity", float(row[6]), command[1], 1e-12)]
        for what, got, want, tol in checks:
            worst = max(worst, abs(got - want) / max(1.0, abs(want)))
            if abs(got - want) > tol:
                sys.exit(f"FAIL: row {k}: {what} = {got!r}, closed form {want!r} (|diff| {abs(got - want):.3g})")
    print(f"ok: {len(data)} rows of {name} match the closed form (largest relative difference {worst:.3g})")


if __name__ == "__main__":
    main()
