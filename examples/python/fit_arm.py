"""The worked example of docs/fitting.md: a log of the arm made by featherdrive from parameters
the fit does not know (joint2: 600 Nm/rad, 12 Nms/rad, 0.08 kg m²; joint4: 300, 6, 0.04; a
2-step delay; Gaussian noise of 1e-4 rad on q), fitted from examples/arm7_fit.yaml's guesses.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/fit_arm.py [OUT_DIR]

writes OUT_DIR/log.csv (default out/fit_arm) and the fit's outputs there, and prints the table.
"""
import os
import sys

import numpy as np

import featherdrive as fd

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, os.pardir, "arm7_fit.yaml")
TRUTH = {"joint2": (600.0, 12.0, 0.08), "joint4": (300.0, 6.0, 0.04)}
DELAY, NOISE, SECONDS = 2, 1e-4, 2.0


def make_log(path):
    scene = fd.load_scene(SCENE)
    sim = fd.make_simulation(scene)
    model = scene.model
    armature = np.array(model.armature)
    for joint, (kp, kd, arm) in TRUTH.items():
        drive = sim.drive(joint)
        drive.stiffness, drive.damping = kp, kd
        sim.set_drive(joint, drive)
        armature[model.dof_index(joint)] = arm
    # Armature is part of the model: a batch of one carries the changed copy.
    batch = fd.Batch(sim, 1)
    batch.set_armature(armature)
    dt = scene.options.dt
    t = dt * np.arange(int(round(SECONDS / dt)) + 1)
    chirp = 2 * np.pi * (0.5 * t + 2.0 * t ** 2 / t[-1])  # 0.5 Hz rising to 4.5 Hz
    targets = 0.3 * np.sin(chirp[:, None] + np.arange(model.nv)[None, :])
    q, qd = [np.array(batch.q[0])], [np.array(batch.qd[0])]
    for k in range(t.size - 1):
        batch.set_drive_targets(targets[max(k - DELAY, 0)])
        batch.step()
        q.append(np.array(batch.q[0]))
        qd.append(np.array(batch.qd[0]))
    q = np.array(q) + NOISE * np.random.default_rng(0).standard_normal((t.size, model.nv))
    names = model.dof_names
    header = ",".join(["t"] + [f"{c}:{n}" for c in ("q", "qd", "target") for n in names])
    np.savetxt(path, np.column_stack([t, q, np.array(qd), targets]), delimiter=",",
               header=header, comments="", fmt="%.17g")


def main(out):
    os.makedirs(out, exist_ok=True)
    log = os.path.join(out, "log.csv")
    make_log(log)
    result = fd.fit(SCENE, log, out=out, threads=1)
    print(result.table())
    print(f"wrote {log}, {result.scene_file}, {result.plot_file}")
    return result


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join("out", "fit_arm"))
