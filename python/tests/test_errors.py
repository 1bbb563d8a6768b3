"""Bad input raises ValueError with a message naming what was wrong."""
import numpy as np
import pytest

import featherdrive as fd


@pytest.fixture
def sim(arm):
    return fd.Simulation(arm)


@pytest.mark.parametrize("method, args, message", [
    ("set_q", (np.zeros(3),), r"q has shape \(3,\), expected \(7,\)"),
    ("set_q", (np.zeros((7, 1)),), r"q has shape \(7, 1\), expected \(7,\)"),
    ("set_qd", (np.zeros(8),), r"qd has shape \(8,\), expected \(7,\)"),
    ("set_applied_force", (np.zeros(6),), r"applied_force has shape \(6,\)"),
    ("set_drive_targets", (np.zeros(5), np.zeros(7)), r"positions has shape \(5,\), expected \(7,\)"),
    ("set_drive_targets", (np.zeros(7), np.zeros((2, 7))), r"velocities has shape \(2, 7\)"),
    ("set_drive_gains", (np.zeros(4), np.zeros(7)), r"stiffness has shape \(4,\)"),
    ("set_drive_gains", (np.zeros(7), np.zeros(9)), r"damping has shape \(9,\)"),
])
def test_wrong_shapes(sim, method, args, message):
    with pytest.raises(ValueError, match=message):
        getattr(sim, method)(*args)


@pytest.mark.parametrize("bad, dtype", [
    (np.array(["a"] * 7), "<U1"),
    (np.zeros(7, dtype=complex), "complex128"),
    (np.zeros(7, dtype=bool), "bool"),
    ([None] * 7, "object"),
])
def test_wrong_dtypes(sim, bad, dtype):
    with pytest.raises(ValueError, match=f"positions has dtype {dtype}"):
        sim.set_drive_targets(bad, np.zeros(7))
    with pytest.raises(ValueError, match=f"q has dtype {dtype}"):
        sim.set_q(bad)


def test_other_real_dtypes_are_accepted(sim):
    sim.set_drive_targets(np.arange(7, dtype=np.int32), [0.0] * 7)
    sim.set_q(np.full(7, 0.5, dtype=np.float32))
    assert sim.drive("joint7").target_position == 6.0 and sim.q[6] == 0.5


def test_non_finite_values(sim):
    with pytest.raises(ValueError, match=r"q\[2\] = nan is not finite"):
        sim.set_q([0, 0, np.nan, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="joint3.*target_position = inf"):
        sim.set_drive_targets([0, 0, np.inf, 0, 0, 0, 0])


def test_unknown_joint_names(sim):
    with pytest.raises(ValueError, match="no joint named 'elbow'"):
        sim.set_drive("elbow", fd.Drive(stiffness=1.0))
    with pytest.raises(ValueError, match="no joint named 'wrist'"):
        sim.set_drive_target("wrist", 0.1, 0.0)
    with pytest.raises(ValueError, match="no joint named 'knee'"):
        sim.set_joint_limits("knee", -1.0, 1.0)
    with pytest.raises(ValueError, match=r"dof index 7 is out of range \[0, 7\)"):
        sim.drive(7)
    with pytest.raises(ValueError, match="expected a joint name"):
        sim.drive(1.5)


def test_bad_gains_name_the_joint_and_change_nothing(sim):
    sim.set_drive_gains(np.full(7, 100.0), np.full(7, 10.0))
    kp = np.full(7, 200.0)
    kp[3] = -5.0
    with pytest.raises(ValueError, match=r"dof 3: drive on joint 'joint4': stiffness = -5 must be finite and >= 0"):
        sim.set_drive_gains(kp, np.full(7, 10.0))
    assert [sim.drive(d).stiffness for d in range(7)] == [100.0] * 7
    kd = np.full(7, 10.0)
    kd[6] = np.nan
    with pytest.raises(ValueError, match="joint 'joint7': damping = nan"):
        sim.set_drive_gains(np.full(7, 1.0), kd)
    with pytest.raises(ValueError, match="drive on joint 'joint2': stiffness = -1"):
        sim.set_drive("joint2", fd.Drive(stiffness=-1.0))
    with pytest.raises(ValueError, match="drive on joint 'joint2': max_force = 0 must be > 0"):
        sim.set_drive("joint2", fd.Drive(stiffness=1.0, max_force=0.0))


def test_bad_options(arm):
    with pytest.raises(ValueError, match="solver = 'xyz': must be 'pgs' or 'tgs'"):
        fd.Simulation(arm, solver="xyz")
    with pytest.raises(ValueError, match="dt = 0 must be finite and > 0"):
        fd.Simulation(arm, dt=0.0)
    with pytest.raises(ValueError, match="position_iterations = 0 must be >= 1"):
        fd.Batch(arm, 2, position_iterations=0)
    with pytest.raises(ValueError, match="drive type = 'spring'"):
        fd.Simulation(arm).set_drive_gains(1.0, 1.0, "spring")
    with pytest.raises(ValueError, match="step count = -1 must be >= 0"):
        fd.Simulation(arm).step(-1)


def test_batch_errors(arm):
    batch = fd.Batch(arm, 4)
    with pytest.raises(ValueError, match=r"positions has shape \(3, 7\), expected \(4, 7\) or \(7,\)"):
        batch.set_drive_targets(np.zeros((3, 7)))
    with pytest.raises(ValueError, match=r"q has shape \(4, 6\)"):
        batch.set_q(np.zeros((4, 6)))
    with pytest.raises(ValueError, match="stiffness has dtype complex128"):
        batch.set_drive_gains(np.zeros((4, 7), dtype=complex), np.zeros((4, 7)))
    kp = np.full((4, 7), 10.0)
    kp[2, 1] = -1.0
    with pytest.raises(ValueError, match="copy 2: set_drive_gains: dof 1: drive on joint 'joint2': stiffness = -1"):
        batch.set_drive_gains(kp, np.zeros((4, 7)))
    assert all(batch.sim(i).drive(1).type == fd.DriveType.none for i in range(4))
    with pytest.raises(ValueError, match=r"qd\[1, 3\] = nan is not finite"):
        qd = np.zeros((4, 7))
        qd[1, 3] = np.nan
        batch.set_qd(qd)
    with pytest.raises(ValueError, match="no joint named 'hip'"):
        batch.set_drive("hip", fd.Drive())
    with pytest.raises(ValueError, match=r"copy index 4 is out of range \[0, 4\)"):
        batch.sim(4)
    with pytest.raises(ValueError, match="num_threads = -1 must be >= 0"):
        batch.num_threads = -1
    with pytest.raises(ValueError, match="count = 0 must be >= 1"):
        fd.Batch(arm, 0)


def test_model_and_file_errors(tmp_path):
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("base", "", 0.0, [0, 0, 0], np.zeros((3, 3)), fd.fixed_joint("world")))
    b.add_link(fd.make_link("arm", "base", -1.0, [0, 0, 0], np.eye(3), fd.revolute_joint("j", [0, 0, 1])))
    with pytest.raises(fd.ModelError, match="arm") as err:
        b.build()
    assert isinstance(err.value, ValueError)
    with pytest.raises(ValueError, match=r"axis has shape \(2,\), expected \(3,\)"):
        fd.revolute_joint("j", [0, 1])
    with pytest.raises(ValueError, match=r"inertia has shape \(3,\), expected \(3, 3\)"):
        fd.make_link("l", "", 1.0, [0, 0, 0], [1, 1, 1], fd.fixed_joint("w"))
    missing = tmp_path / "missing.urdf"
    with pytest.raises(ValueError, match="missing.urdf"):
        fd.load_urdf(str(missing))
    bad = tmp_path / "bad.yaml"
    bad.write_text("model: nowhere.urdf\nsteps: 10\nsolver: {type: xgs}\n")
    with pytest.raises(ValueError, match="bad.yaml"):
        fd.load_scene(str(bad))
