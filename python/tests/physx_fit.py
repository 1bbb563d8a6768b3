"""Cross-engine: a log made by PhysX 5.6.1 itself (the harness of tests/physx, float32) from
the gains and armature it was given, fitted by featherdrive from starting values off by 2x:
within 1 % of PhysX's. Run by ctest as python.fit_physx (the physx fixture installs the harness),
not with the other python/tests: it needs node and the harness."""
import os

import numpy as np

import featherdrive as fd
from conftest import ARM
from test_fit import DT, FIT_GAINS, ROWS, TRUTH, chirp_targets, worst_error, write_log

# PhysX's defaults on both sides (compat: physx); no joint friction: the harness cannot set it.
ZERO_FRICTION = ", ".join(f"joint{i}: {{friction: {{static: 0, dynamic: 0, viscous: 0}}"
                          + (", armature: 0.08" if i == 2 else ", armature: 0.04" if i == 4 else "")
                          + "}" for i in range(1, 8))
SCENE = (f"model: {ARM}\nsteps: {ROWS - 1}\ndt: {DT!r}\ncompat: physx\n"
         "solver: {type: tgs, position_iterations: 4, velocity_iterations: 1}\n"
         "drive_defaults: {type: force, stiffness: 400, damping: 10}\n"
         "drives: {joint2: {stiffness: 600, damping: 12}, joint4: {stiffness: 300, damping: 6}}\n"
         f"joints: {{{ZERO_FRICTION}}}\n")
# test_fit's unknowns (TRUTH: what PhysX is given), starting 2x off; no delay.
FIT = FIT_GAINS.replace("    - {quantity: delay, joints: all, bounds: [0, 2]}\n", "")


def test_fit_recovers_what_physx_was_given(tmp_path):
    scene = fd.parse_scene(SCENE, str(tmp_path / "physx.yaml"))
    targets = chirp_targets(scene.model.nv)
    harness = os.path.join(os.path.dirname(fd.__file__), os.pardir, "physx")
    q, qd = fd.run_physx(fd.make_simulation(scene), ROWS - 1, targets[:-1], [harness])
    assert q.shape == (ROWS, scene.model.nv) and np.abs(q).max() > 0.1  # PhysX moved the arm
    write_log(tmp_path / "physx.csv", scene.model.dof_names, q, qd, targets)
    (tmp_path / "fit.yaml").write_text(SCENE + FIT)
    result = fd.fit(str(tmp_path / "fit.yaml"), str(tmp_path / "physx.csv"), threads=1)
    print(result.table(), worst_error(result, TRUTH))
    assert worst_error(result, TRUTH) < 0.01, result.table()
