"""Names and orders (issue 20): link, joint and dof names against the URDF text read with
xml.etree, the maps between the file's joint order and the dof order, the live joint accessor
against the whole-vector views, bad names, and targets refused on dofs without a drive."""
import gc
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import featherdrive as fd
from conftest import ARM, ROOT

LEAF_FIRST = ROOT / "tests" / "data" / "leaf_joint_first.urdf"


def urdf_joints(path):
    """(name, type, child) of every <joint>, in file order, read with xml.etree."""
    root = ET.parse(path).getroot()
    return [(j.get("name"), j.get("type"), j.find("child").get("link"))
            for j in root.findall("joint")]


def test_model_names_follow_the_urdf(arm):
    joints = urdf_joints(ARM)
    moving = [name for name, kind, _ in joints if kind != "fixed"]
    assert arm.dof_names == moving  # a chain: file order is depth-first order
    assert arm.joint_names[1:] == moving
    assert arm.link_names[1:] == [child for _, kind, child in joints if kind != "fixed"]
    assert len(arm.link_names) == len(arm.joint_names) == arm.num_links()


@pytest.mark.parametrize("fixed_base", [True, False])
def test_file_order_and_dof_order_map_both_ways(fixed_base):
    robot = fd.load_urdf(str(LEAF_FIRST), fd.UrdfOptions(fixed_base=fixed_base))
    model = robot.model
    joints = urdf_joints(LEAF_FIRST)
    assert robot.urdf_joint_names == [name for name, _, _ in joints]
    dofs = robot.dof_of_urdf_joint
    assert dofs.dtype == np.int64 and dofs.shape == (len(joints),)
    first_dof = 0 if fixed_base else 6
    # The first dof is not the file's first joint (as in DRC-Hubo).
    assert robot.urdf_joint_names[robot.urdf_joint_of_dof[first_dof]] != joints[0][0]
    for j, (name, kind, child) in enumerate(joints):
        if kind == "fixed":
            assert dofs[j] == -1
        else:
            assert model.dof_names[dofs[j]] == name
            assert robot.urdf_joint_of_dof[dofs[j]] == j
            assert model.link_names[robot.link_of_urdf_joint[j]] == child
    assert list(robot.urdf_joint_of_dof[:first_dof]) == [-1] * first_dof
    assert sorted(robot.urdf_joint_of_dof[first_dof:]) == [j for j, (_, k, _) in
                                                           enumerate(joints) if k != "fixed"]
    with pytest.raises(ValueError):
        robot.dof_of_urdf_joint[0] = 5  # read-only


def test_joint_accessor_reads_the_simulation_at_call_time(arm):
    sim = fd.Simulation(arm, dt=0.01, solver="tgs", stiffness=800.0, damping=30.0)
    j3 = sim.joint("joint3")
    d = arm.dof_index("joint3")
    assert (j3.name, j3.dof, j3.nv, j3.type) == ("joint3", d, 1, fd.JointType.revolute)
    j3.set_target(0.4, velocity=0.1)
    assert (sim.drive(d).target_position, sim.drive(d).target_velocity) == (0.4, 0.1)
    sim.set_applied_force(np.arange(7.0))
    sim.step(20)
    for field in ("qd", "drive_force", "limit_force", "friction_force", "applied_force"):
        assert getattr(j3, field) == getattr(sim, field)[d], field
    assert j3.q == sim.q[arm.links[arm.dof_link[d]].q_index]
    before = j3.q
    sim.step(5)
    assert j3.q != before and j3.q == sim.q[d]  # live, not a snapshot
    # Settings through the accessor are the simulation's.
    j3.drive = fd.Drive("acceleration", stiffness=50.0, damping=5.0)
    assert sim.drive("joint3").type == fd.DriveType.acceleration
    j3.limits = (-0.5, 0.25)
    assert (sim.lower_limit(d), sim.upper_limit(d)) == (-0.5, 0.25) == j3.limits
    j3.friction = fd.JointFriction(0.3, 0.2, 0.1)
    assert sim.joint_friction(d).static_effort == 0.3 == j3.friction.static_effort
    j3.max_velocity = 1.5
    assert sim.max_joint_velocity(d) == 1.5 == j3.max_velocity
    # The accessor keeps its simulation alive.
    j = fd.Simulation(arm).joint("joint1")
    gc.collect()
    assert j.q == 0.0 and j.drive.type == fd.DriveType.none


def test_multi_dof_joints_give_arrays():
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("base", "", 1.0, [0, 0, 0], np.eye(3) * 0.01,
                            fd.floating_joint("root")))
    b.add_link(fd.make_link("arm", "base", 1.0, [0, 0, 0.1], np.eye(3) * 0.01,
                            fd.spherical_joint("ball", [0, 0, 0.2])))
    model = b.build()
    sim = fd.Simulation(model)
    q = np.array(sim.q)
    q[7:] = [np.cos(0.2), np.sin(0.2), 0.0, 0.0]
    sim.set_q(q)
    root, ball = sim.joint("root"), sim.joint("ball")
    assert root.q.shape == (7,) and ball.q.shape == (4,) and ball.qd.shape == (3,)
    np.testing.assert_array_equal(ball.q, sim.q[7:])
    assert root.nv == 6 and len(root.drive) == 6
    with pytest.raises(ValueError, match="no target|drive"):
        ball.set_target(0.1)


def test_bad_joint_names_list_the_nearest_or_the_valid_ones(arm):
    sim = fd.Simulation(arm)
    with pytest.raises(ValueError, match=r"no joint named 'joint33'; did you mean: joint3"):
        sim.joint("joint33")
    with pytest.raises(ValueError, match=r"no joint named 'elbow'; the joints are: joint1, "
                                         r"joint2, joint3, joint4, joint5, joint6, joint7$"):
        sim.joint("elbow")
    with pytest.raises(ValueError, match="joint 'root_joint' is fixed: it has no degree"):
        sim.joint(arm.joint_names[0])  # the welded root's joint
    with pytest.raises(ValueError, match="no joint named 'world_to_base'"):
        sim.joint("world_to_base")  # a URDF fixed joint, merged away
    with pytest.raises(TypeError):
        sim.joint(3)
    with pytest.raises(ValueError, match="did you mean: arm7.urdf"):
        fd.example_path("arm7.urd")


def test_targets_on_dofs_without_a_drive_are_refused(arm):
    sim = fd.Simulation(arm)
    with pytest.raises(ValueError, match=r"joint 'joint1' \(dof 0\) has no drive.*set_drive_gains"):
        sim.set_drive_targets(np.full(7, 0.3))
    with pytest.raises(ValueError, match=r"joint 'joint4' \(dof 3\) has no drive"):
        sim.set_drive_target("joint4", 0.3)
    with pytest.raises(ValueError, match=r"has no drive"):
        sim.joint("joint4").set_target(0.0)
    sim.set_drive_targets(np.zeros(7))  # zeros on undriven dofs: accepted
    batch = fd.Batch(arm, 3)
    with pytest.raises(ValueError, match=r"joint 'joint1' \(dof 0\) has no drive"):
        batch.set_drive_targets(np.full((3, 7), 0.1))
    # One driven joint: the vector may set it, not the others.
    sim.set_drive("joint2", fd.Drive(stiffness=100.0, damping=10.0))
    target = np.zeros(7)
    target[1] = 0.2
    sim.set_drive_targets(target)
    assert sim.drive("joint2").target_position == 0.2
    target[5] = 0.1
    with pytest.raises(ValueError, match=r"joint 'joint6' \(dof 5\)"):
        sim.set_drive_targets(target)


def test_constructor_gains_equal_set_drive_gains(arm):
    a = fd.Simulation(arm, dt=0.01, stiffness=2e4, damping=100.0)
    b = fd.Simulation(arm, dt=0.01)
    b.set_drive_gains(np.full(7, 2e4), np.full(7, 100.0))
    for s in (a, b):
        s.set_drive_targets(np.linspace(-0.3, 0.3, 7))
        s.step(30)
    assert a.q.tobytes() == b.q.tobytes()
    c = fd.Simulation(arm, stiffness=np.arange(7.0), drive_type="acceleration")
    assert [c.drive(k).stiffness for k in range(7)] == list(range(7))
    assert c.drive(0).type == fd.DriveType.acceleration and c.drive(3).damping == 0.0
    # A floating root's dofs get no drive from a scalar.
    robot = fd.load_urdf(str(LEAF_FIRST), fd.UrdfOptions(fixed_base=False))
    f = fd.Simulation(robot.model, stiffness=10.0, damping=1.0)
    assert [f.drive(k).type for k in range(6)] == [fd.DriveType.none] * 6
    assert f.drive(6).type == fd.DriveType.force and f.drive(6).stiffness == 10.0
    with pytest.raises(ValueError, match="stiffness = -1"):
        fd.Simulation(arm, stiffness=-1.0)
    with pytest.raises(ValueError, match=r"stiffness has shape \(3,\)"):
        fd.Simulation(arm, stiffness=np.ones(3))
    with pytest.raises(ValueError, match="drive_type = 'acceleration' needs stiffness or damping"):
        fd.Simulation(arm, drive_type="acceleration")
    with pytest.raises(ValueError, match="drive type = 'spring'"):
        fd.Simulation(arm, stiffness=1.0, drive_type="spring")


def test_batch_constructor_gains_equal_single_simulations(arm):
    # Batch(model, ..., stiffness, damping) as Simulation's constructor: every environment equals
    # a lone simulation given the gains by set_drive_gains.
    batch = fd.Batch(arm, 3, dt=0.01, stiffness=2e4, damping=100.0)
    lone = fd.Simulation(arm, dt=0.01)
    lone.set_drive_gains(np.full(7, 2e4), np.full(7, 100.0))
    targets = np.linspace(-0.3, 0.3, 7)
    batch.set_drive_targets(targets)
    lone.set_drive_targets(targets)
    batch.step(30)
    lone.step(30)
    for i in range(3):
        assert np.max(np.abs(batch.q[i] - lone.q)) <= 1e-12  # SIMD lanes: another order
    with pytest.raises(ValueError, match="stiffness = -1"):
        fd.Batch(arm, 2, stiffness=-1.0)
    with pytest.raises(ValueError, match="has no drive"):
        fd.Batch(arm, 2).set_drive_targets(targets)


# ---- frames of links merged through fixed joints (issue 33) -------------------------------------

def urdf_origin(path, joint):
    """(xyz, R) of a <joint>'s <origin>, read with xml.etree (R = Rz(y) Ry(p) Rx(r))."""
    origin = next(j for j in ET.parse(path).getroot().findall("joint")
                  if j.get("name") == joint).find("origin")
    xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
    r, p, y = (float(v) for v in origin.get("rpy", "0 0 0").split())
    rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    return xyz, rz @ ry @ rx


def tcp_pose(rotation, position):
    """The arm's tcp from link7's pose, composing the URDF's fixed origins by hand:
    link7 -> hand (hand_joint) -> tcp (tcp_joint)."""
    p1, r1 = urdf_origin(ARM, "hand_joint")
    p2, r2 = urdf_origin(ARM, "tcp_joint")
    return rotation @ r1 @ r2, position + rotation @ (p1 + r1 @ p2)


def test_merged_links_keep_their_frames_for_every_query(arm):
    assert "tcp" not in arm.link_names and "hand" not in arm.link_names  # merged into link7
    sim = fd.Simulation(arm)
    sim.set_q(np.linspace(-0.9, 1.1, arm.nv))
    R7, p7 = sim.link_pose("link7")
    R, p = tcp_pose(R7, p7)
    Rt, pt = sim.link_pose("tcp")
    np.testing.assert_allclose(Rt, R, atol=1e-12)
    np.testing.assert_allclose(pt, p, atol=1e-12)
    point = np.array([0.01, -0.02, 0.03])  # in the tcp frame
    np.testing.assert_allclose(sim.frame_position("tcp", point), p + R @ point, atol=1e-12)
    np.testing.assert_allclose(fd.frame_position(arm, sim.q, "tcp", point), p + R @ point,
                               atol=1e-12)
    # The Jacobian's linear rows against central differences of the frame's position.
    J = sim.jacobian("tcp", point)
    h = 1e-6
    for d in range(arm.nv):
        dq = np.zeros(arm.nv)
        dq[d] = h
        diff = (fd.frame_position(arm, sim.q + dq, "tcp", point) -
                fd.frame_position(arm, sim.q - dq, "tcp", point)) / (2 * h)
        np.testing.assert_allclose(J[3:, d], diff, atol=1e-8)
    # local: the same rows in the tcp's own axes.
    local = sim.jacobian("tcp", point, "local")
    np.testing.assert_allclose(local[:3], R.T @ J[:3], atol=1e-12)
    np.testing.assert_allclose(local[3:], R.T @ J[3:], atol=1e-12)
    sim.set_qd(np.linspace(0.5, -0.4, arm.nv))
    np.testing.assert_allclose(sim.frame_velocity("tcp", point), J @ sim.qd, atol=1e-12)
    np.testing.assert_allclose(sim.frame_velocity("tcp", point, "local"), local @ sim.qd,
                               atol=1e-12)


def test_batch_frame_positions_of_a_merged_link(arm):
    batch = fd.Batch(arm, 3)
    q = np.stack([np.linspace(-0.5, 0.5, arm.nv) * k for k in (0.0, 1.0, 2.0)])
    batch.set_q(q)
    point = np.array([0.0, 0.05, 0.0])
    got = batch.frame_positions("tcp", point)
    for i in range(3):
        R, p = tcp_pose(*fd.link_pose(arm, q[i], "link7"))
        np.testing.assert_allclose(got[i], p + R @ point, atol=1e-12)


def test_unknown_frame_names_the_nearest(arm):
    sim = fd.Simulation(arm)
    for query in (lambda n: sim.frame_position(n, [0, 0, 0]), sim.link_pose, sim.jacobian,
                  lambda n: fd.Batch(arm, 1).frame_positions(n)):
        with pytest.raises(ValueError, match=r"^no link or frame named 'tpc'; nearest: 'tcp'"):
            query("tpc")
