"""Cross-engine: a log made by PhysX 5.6.1 itself (the harness of tests/physx, float32) from
the gains and armature it was given, fitted by featherdrive from starting values off by 2x:
within 1 % of PhysX's. Run by ctest as python.fit_physx (the physx fixture installs the harness),
not with the other python/tests: it needs node and the harness."""
import csv
import os

import numpy as np

import featherdrive as fd
from conftest import ARM

DT = 1.0 / 240.0
ROWS = 241
# PhysX's defaults on both sides (compat: physx); no joint friction: the harness cannot set it.
ZERO_FRICTION = ", ".join(f"joint{i}: {{friction: {{static: 0, dynamic: 0, viscous: 0}}"
                          + (", armature: 0.08" if i == 2 else ", armature: 0.04" if i == 4 else "")
                          + "}" for i in range(1, 8))
SCENE = (f"model: {ARM}\nsteps: {ROWS - 1}\ndt: {DT!r}\ncompat: physx\n"
         "solver: {type: tgs, position_iterations: 4, velocity_iterations: 1}\n"
         "drive_defaults: {type: force, stiffness: 400, damping: 10}\n"
         "drives: {joint2: {stiffness: 600, damping: 12}, joint4: {stiffness: 300, damping: 6}}\n"
         f"joints: {{{ZERO_FRICTION}}}\n")
FIT = """fit:
  parameters:
    - {quantity: stiffness, joints: [joint2, joint4], bounds: [50, 5000], initial: 1200}
    - {quantity: damping, joints: [joint2], bounds: [0.5, 100], initial: 6}
    - {quantity: damping, joints: [joint4], bounds: [0.5, 100], initial: 12}
    - {quantity: armature, joints: [joint2], bounds: [0.001, 1], initial: 0.04}
    - {quantity: armature, joints: [joint4], bounds: [0.001, 1], initial: 0.08}
"""
GIVEN = {("stiffness", "joint2"): 600, ("stiffness", "joint4"): 300,
         ("damping", "joint2"): 12, ("damping", "joint4"): 6,
         ("armature", "joint2"): 0.08, ("armature", "joint4"): 0.04}


def test_fit_recovers_what_physx_was_given(tmp_path):
    scene = fd.parse_scene(SCENE, str(tmp_path / "physx.yaml"))
    sim = fd.make_simulation(scene)
    nv = scene.model.nv
    t = DT * np.arange(ROWS)
    phase = 2 * np.pi * (0.5 * t + 3.5 * t ** 2 / (2 * t[-1]))
    targets = 0.3 * np.sin(phase[:, None] + np.arange(nv)[None, :])
    harness = os.path.join(os.path.dirname(fd.__file__), os.pardir, "physx")
    q, qd = fd.run_physx(sim, ROWS - 1, targets[:-1], [harness])
    assert q.shape == (ROWS, nv) and np.abs(q).max() > 0.1  # PhysX moved the arm
    names = scene.model.dof_names
    with open(tmp_path / "physx.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t"] + [f"q:{n}" for n in names] + [f"qd:{n}" for n in names] +
                   [f"target:{n}" for n in names])
        for k in range(ROWS):
            w.writerow([repr(t[k])] + [repr(x) for x in q[k]] + [repr(x) for x in qd[k]] +
                       [repr(x) for x in targets[k]])
    (tmp_path / "fit.yaml").write_text(SCENE + FIT)
    result = fd.fit(str(tmp_path / "fit.yaml"), str(tmp_path / "physx.csv"), threads=1)
    errors = {k: result.value(*k) / v - 1 for k, v in GIVEN.items()}
    print(result.table(), errors)
    assert max(abs(e) for e in errors.values()) < 0.01, result.table()
