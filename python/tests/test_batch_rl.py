"""Batch as an RL backend (issue 20): states are views of the batch's storage, setters take
env_ids and broadcast scalars and rows, reset restarts some environments and leaves the others'
bits alone, randomised environments equal Simulations built with their parameters, and
observations come back in one array."""
import gc

import numpy as np
import pytest

import featherdrive as fd
from conftest import ARM

FIELDS = ("q", "qd", "applied_force", "drive_force", "limit_force", "friction_force",
          "velocity_limit_force")



@pytest.fixture(autouse=True)
def scalar_steps(monkeypatch):
    """These tests hold each environment to a Simulation built with its parameters, bit for bit:
    true of the Batch without SIMD lanes (test_batch.py checks the lanes within 1e-12)."""
    monkeypatch.setenv("FEATHERDRIVE_SIMD", "scalar")

def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def test_states_are_read_only_views_of_the_environments(arm):
    batch = fd.Batch(arm, 4)
    views = {name: getattr(batch, name) for name in FIELDS}
    for name, view in views.items():
        assert view.shape == (4, arm.nq if name == "q" else arm.nv)
        assert not view.flags.writeable
        with pytest.raises(ValueError):
            view[0, 0] = 1.0
        for i in range(4):
            assert np.shares_memory(view[i], getattr(batch.sim(i), name))
    batch.set_drive_gains(1000.0, 50.0)
    batch.set_drive_targets(0.3)
    batch.step(5)
    # The views taken before the step show its result, and keep the batch alive.
    q = views["q"]
    np.testing.assert_array_equal(q, batch.q)
    assert np.all(q[:, 0] > 0.0) and np.all(views["drive_force"] != 0.0)
    expected = np.array(q)
    del batch, views
    gc.collect()
    np.testing.assert_array_equal(q, expected)


def test_scalars_and_rows_broadcast_over_env_ids(arm):
    batch = fd.Batch(arm, 5, solver="tgs")
    batch.set_drive_gains(2000.0, 80.0)
    batch.set_drive_targets(0.3, env_ids=[1, 3])
    batch.set_drive_targets(np.linspace(-0.2, 0.2, arm.nv), 0.1,
                            env_ids=np.array([4], dtype=np.uint8))
    batch.set_qd(np.arange(2 * arm.nv).reshape(2, arm.nv) * 0.01, env_ids=(0, 2))
    batch.step(30)
    for i in range(5):
        sim = fd.Simulation(arm, solver="tgs")
        sim.set_drive_gains(2000.0, 80.0)
        if i in (1, 3):
            sim.set_drive_targets(np.full(arm.nv, 0.3))
        if i == 4:
            sim.set_drive_targets(np.linspace(-0.2, 0.2, arm.nv), np.full(arm.nv, 0.1))
        if i in (0, 2):
            sim.set_qd((np.arange(arm.nv) + (arm.nv if i == 2 else 0)) * 0.01)
        sim.step(30)
        # SIMD lanes: within 1e-12 of the lone step (another operation order).
        assert np.max(np.abs(batch.q[i] - sim.q)) <= 1e-12, f"env {i}"
        np.testing.assert_array_equal(bits(batch.drive_force[i]), bits(sim.drive_force))


def test_env_ids_and_values_are_checked_before_anything_changes(arm):
    batch = fd.Batch(arm, 4)
    q = np.array(batch.q)
    with pytest.raises(ValueError, match=r"env_ids\[1\] = 9 is out of range \[0, 4\)"):
        batch.set_q(0.1, env_ids=[0, 9])
    with pytest.raises(ValueError, match=r"env_ids\[2\] = 1 appears twice \(also env_ids\[0\]\)"):
        batch.set_q(0.1, env_ids=[1, 2, 1])
    with pytest.raises(ValueError, match=r"env_ids\[0\] = -1 is out of range"):
        batch.reset([-1])
    with pytest.raises(TypeError, match="env_ids must hold integers, not float64"):
        batch.set_q(0.1, env_ids=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"q has shape \(3, 7\), expected \(2, 7\) or \(7,\)"):
        batch.set_q(np.zeros((3, 7)), env_ids=[0, 1])
    bad = np.zeros((2, 7))
    bad[1, 3] = np.inf
    with pytest.raises(ValueError, match=r"environment 3: q\[3\] = inf is not finite"):
        batch.set_q(bad, env_ids=[2, 3])
    with pytest.raises(ValueError, match="environment 1: set_drive_gains: dof 0"):
        batch.set_drive_gains([[10.0] * 7, [-1.0] + [10.0] * 6], 1.0, env_ids=[0, 1])
    np.testing.assert_array_equal(batch.q, q)
    assert all(batch.sim(i).drive(0).type == fd.DriveType.none for i in range(4))
    with pytest.raises(ValueError, match="observe: field 'tau' is not one of"):
        batch.observe(["q", "tau"])
    with pytest.raises(ValueError, match=r"link index 99 is out of range"):
        batch.frame_positions(99)
    with pytest.raises(ValueError, match="no link named 'hand'"):
        batch.set_link_mass("hand", 1.0)
    with pytest.raises(ValueError, match="environment 2: model: link 'link3': mass = -1"):
        batch.set_link_mass("link3", [1.0, -1.0], env_ids=[0, 2])
    assert batch.link_mass("link3")[0] == arm.links[arm.link_index("link3")].mass


def state(sim):
    return (b"".join(bits(getattr(sim, f)).tobytes() for f in FIELDS), sim.step_count,
            sim.time)


def test_reset_restarts_some_environments_and_leaves_the_others_bit_for_bit(arm):
    proto = fd.Simulation(arm, solver="tgs")
    proto.set_q(arm.neutral_configuration() + 0.2)
    proto.set_drive_gains(1500.0, 40.0)
    batch = fd.Batch(proto, 6)
    batch.set_drive_targets(np.linspace(-0.5, 0.5, 6)[:, None] * np.ones(arm.nv))
    batch.set_applied_force(0.5, env_ids=[1, 4])
    batch.step(40)
    before = [state(batch.sim(i)) for i in range(6)]
    batch.reset([4, 1])
    for i in (0, 2, 3, 5):
        assert state(batch.sim(i)) == before[i]
    for i in (1, 4):
        np.testing.assert_array_equal(bits(batch.q[i]), bits(proto.q))
        assert not batch.qd[i].any() and not batch.applied_force[i].any()
        assert not batch.drive_force[i].any()
        assert batch.sim(i).step_count == 0 and batch.sim(i).time == 0.0
    batch.step(25)
    for i in (1, 4):
        fresh = proto.copy()
        fresh.set_drive_targets(np.full(arm.nv, np.linspace(-0.5, 0.5, 6)[i]))
        fresh.step(25)
        np.testing.assert_array_equal(bits(batch.q[i]), bits(fresh.q))
    # q and qd given: one row each, or one for all.
    batch.reset([0, 5], q=[np.full(arm.nv, 0.1), np.full(arm.nv, -0.1)], qd=0.25)
    np.testing.assert_array_equal(batch.q[5], np.full(arm.nv, -0.1))
    np.testing.assert_array_equal(batch.qd[0], np.full(arm.nv, 0.25))
    batch.reset(None)
    np.testing.assert_array_equal(batch.q, np.tile(proto.q, (6, 1)))


def arm_with(mass3=None, com2=None, armature=None):
    """The arm built from its URDF's links with some parameters replaced."""
    robot = fd.load_urdf(str(ARM))
    links = robot.links
    by_name = {l.name: l for l in links}
    if mass3 is not None:
        l = by_name["link3"]
        l.inertia = np.array(l.inertia) * (mass3 / l.mass)
        l.mass = mass3
    if com2 is not None:
        by_name["link2"].com = com2
    if armature is not None:
        for l in links:
            if l.joint.type == fd.JointType.revolute:
                j = l.joint
                j.armature = [armature]
                l.joint = j
    robot.links = links
    robot.rebuild()
    return robot.model


@pytest.mark.parametrize("threads", [1, 2])
def test_randomised_environments_equal_simulations_built_with_their_parameters(arm, threads):
    batch = fd.Batch(arm, 4, dt=0.01, solver="pgs")
    batch.num_threads = threads
    batch.set_drive_gains(3000.0, 60.0)
    batch.set_drive_targets(0.4)
    batch.set_link_mass("link3", [1.9, 0.7], env_ids=[1, 3])
    batch.set_link_com("link2", [0.01, 0.02, 0.05], env_ids=[3])
    batch.set_armature(0.05, env_ids=[1])
    batch.set_joint_friction(0.4, 0.3, 0.02, env_ids=[3])
    batch.set_joint_limits(-0.3, 0.35, env_ids=[1])
    batch.set_max_joint_velocity(0.8, env_ids=[3])
    batch.set_drive_gains(500.0, 20.0, env_ids=[1])
    batch.step(300)
    plain = fd.Simulation(arm, dt=0.01)
    env1 = fd.Simulation(arm_with(mass3=1.9, armature=0.05), dt=0.01)
    env3 = fd.Simulation(arm_with(mass3=0.7, com2=[0.01, 0.02, 0.05]), dt=0.01)
    for sim in (plain, env1, env3):
        sim.set_drive_gains(3000.0, 60.0)
        sim.set_drive_targets(np.full(arm.nv, 0.4))
    env1.set_drive_gains(500.0, 20.0)
    for d in range(arm.nv):
        env1.set_joint_limits(d, -0.3, 0.35)
        env3.set_joint_friction(d, fd.JointFriction(0.4, 0.3, 0.02))
        env3.set_max_joint_velocity(d, 0.8)
    for sim in (plain, env1, env3):
        sim.step(300)
    for i, sim in enumerate((plain, env1, plain, env3)):
        for f in FIELDS:
            np.testing.assert_array_equal(bits(getattr(batch, f)[i]), bits(getattr(sim, f)),
                                          err_msg=f"env {i} {f}")
    assert not np.array_equal(env1.q, plain.q) and not np.array_equal(env3.q, plain.q)
    m3 = arm.links[arm.link_index("link3")].mass
    np.testing.assert_array_equal(batch.link_mass("link3"), [m3, 1.9, m3, 0.7])
    np.testing.assert_array_equal(batch.link_com("link2")[3], [0.01, 0.02, 0.05])
    assert batch.armature()[1, 0] == 0.05 and batch.armature()[0, 0] == arm.armature[0]
    lower, upper = batch.joint_limits()
    assert lower[1, 2] == -0.3 and upper[0, 2] == arm.upper_limit[2]
    static, dynamic, viscous = batch.joint_friction()
    assert (static[3, 0], dynamic[3, 0], viscous[3, 0]) == (0.4, 0.3, 0.02)
    assert batch.max_joint_velocity()[3, 5] == 0.8


def test_observe_and_frame_positions_gather_every_environment(arm):
    batch = fd.Batch(arm, 6)
    batch.set_q(np.random.default_rng(2).uniform(-1, 1, (6, arm.nq)))
    batch.set_drive_gains(800.0, 30.0)
    batch.set_drive_targets(np.random.default_rng(3).uniform(-1, 1, (6, arm.nv)), 0.2)
    batch.step(3)
    obs = batch.observe(["q", "qd", "target_position", "target_velocity", "drive_force"])
    assert obs.shape == (6, 5 * arm.nv) and obs.flags.writeable
    for i in range(6):
        sim = batch.sim(i)
        np.testing.assert_array_equal(obs[i, :7], sim.q)
        np.testing.assert_array_equal(obs[i, 7:14], sim.qd)
        np.testing.assert_array_equal(obs[i, 14:21], [sim.drive(d).target_position
                                                      for d in range(7)])
        np.testing.assert_array_equal(obs[i, 21:28], 0.2)
        np.testing.assert_array_equal(obs[i, 28:], sim.drive_force)
    point = [0.01, -0.02, 0.1]
    for threads in (1, 2):
        batch.num_threads = threads
        tip = batch.frame_positions("link7", point)
        base = batch.frame_positions(0)
        for i in range(6):
            expected = fd.frame_position(arm, batch.q[i], "link7", point)
            np.testing.assert_allclose(tip[i], expected, rtol=0, atol=1e-15)
            np.testing.assert_array_equal(base[i], fd.link_pose(arm, batch.q[i], 0)[1])
