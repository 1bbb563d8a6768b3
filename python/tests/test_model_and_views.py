"""Building a model in code, reading state as read-only numpy views, and a closed-form check of
one driven dof."""
import gc

import numpy as np
import pytest

import featherdrive as fd

M = 2.5  # kg
BOX = M * 0.1 ** 2 / 6  # inertia of a 0.1 m cube


def slider(gravity=(0.0, 0.0, -9.81)):
    """A 2.5 kg cube sliding along z on a base welded to the world."""
    b = fd.ModelBuilder().set_gravity(gravity)
    b.add_link(fd.make_link("base", "", 0.0, [0, 0, 0], np.zeros((3, 3)), fd.fixed_joint("world")))
    b.add_link(fd.make_link("carriage", "base", M, [0, 0, 0], BOX * np.eye(3),
                            fd.prismatic_joint("slide", [0, 0, 1])))
    return b.build()


def test_model_from_builder():
    model = slider()
    assert (model.nq, model.nv) == (1, 1)
    assert model.dof_names == ["slide"]
    assert model.dof_index("slide") == 0
    assert model.links[model.link_index("carriage")].joint_type == fd.JointType.prismatic
    assert model.links[1].mass == M
    assert not model.floating_base()


def test_urdf_model(arm):
    assert (arm.nq, arm.nv) == (7, 7)
    assert arm.dof_names == [f"joint{i}" for i in range(1, 8)]
    robot = fd.load_urdf(str(__import__("conftest").ARM), fd.UrdfOptions(fixed_base=False))
    assert robot.model.floating_base()
    assert (robot.model.nq, robot.model.nv) == (14, 13)


def test_one_dof_drive_closed_form():
    """For one dof a PGS step of the implicit drive solves m (v1 - v0) = dt (kp (xT - x0 - dt v1) +
    kd (vT - v1)) + dt F exactly, with x1 = x0 + dt v1 (F = m g along the axis)."""
    dt, kp, kd, xt, vt, g = 0.01, 400.0, 20.0, 0.3, 0.1, -9.81
    sim = fd.Simulation(slider(), dt=dt, solver="pgs", position_iterations=4)
    sim.set_drive("slide", fd.Drive(fd.DriveType.force, stiffness=kp, damping=kd,
                                    target_position=xt, target_velocity=vt))
    x, v = 0.0, 0.0
    for _ in range(50):
        sim.step()
        v1 = (M * v + dt * (kp * (xt - x) + kd * vt) + dt * M * g) / (M + dt * dt * kp + dt * kd)
        f = kp * (xt - x - dt * v1) + kd * (vt - v1)
        x, v = x + dt * v1, v1
        assert sim.q[0] == pytest.approx(x, rel=1e-9, abs=1e-12)
        assert sim.qd[0] == pytest.approx(v, rel=1e-9, abs=1e-12)
        assert sim.drive_force[0] == pytest.approx(f, rel=1e-9, abs=1e-9)


def test_views_are_read_only_live_and_keep_the_simulation_alive(arm):
    sim = fd.Simulation(arm, dt=0.01, solver="tgs")
    sim.set_drive_gains(np.full(7, 500.0), np.full(7, 20.0))
    sim.set_drive_targets(np.full(7, 0.3))
    q, qd, f, lim = sim.q, sim.qd, sim.drive_force, sim.limit_force
    for view, n in ((q, arm.nq), (qd, arm.nv), (f, arm.nv), (lim, arm.nv)):
        assert view.shape == (n,) and view.dtype == np.float64
        assert not view.flags.writeable
        with pytest.raises(ValueError):
            view[0] = 1.0
    assert np.shares_memory(sim.q, q)  # no copy: every read views the same memory
    before = np.array(q)
    del sim
    gc.collect()
    # The views hold the simulation: it lives on after `del sim`.
    assert isinstance(q.base, fd.Simulation)
    q.base.step()
    assert q.base.step_count == 1
    assert not np.array_equal(q, before)  # the view follows the step
    assert np.all(np.isfinite(f))


def test_views_follow_steps(arm):
    sim = fd.Simulation(arm)
    sim.set_drive_gains(1000.0, 50.0)
    sim.set_drive_targets(np.full(7, 0.5))
    q = sim.q
    snapshot = np.array(q)
    sim.step(5)
    assert sim.step_count == 5 and sim.time == pytest.approx(5 / 60)
    assert not np.array_equal(q, snapshot)
    np.testing.assert_array_equal(q, sim.q)


def test_drive_settings_round_trip(arm):
    sim = fd.Simulation(arm)
    sim.set_drive("joint3", fd.Drive("acceleration", stiffness=30.0, damping=2.0, max_force=9.0))
    d = sim.drive("joint3")
    assert (d.type, d.stiffness, d.damping, d.max_force) == (fd.DriveType.acceleration, 30.0, 2.0, 9.0)
    assert sim.drive(2).stiffness == 30.0  # the same dof by index
    sim.set_drive_target("joint3", 0.25, -0.5)
    assert (sim.drive("joint3").target_position, sim.drive("joint3").target_velocity) == (0.25, -0.5)
    sim.set_joint_limits("joint2", -0.5, 0.75)
    assert (sim.lower_limit("joint2"), sim.upper_limit("joint2")) == (-0.5, 0.75)
    sim.set_joint_friction("joint1", fd.JointFriction(1.0, 0.5, 0.1))
    assert sim.joint_friction("joint1").viscous == 0.1
    sim.set_max_joint_velocity("joint4", 2.0)
    assert sim.max_joint_velocity("joint4") == 2.0
    sim.set_actuator_envelope("joint5", fd.ActuatorEnvelope(max_effort=40.0))
    assert sim.actuator_envelope("joint5").active()
    # set_drive_gains keeps targets and max_force and sets the type.
    sim.set_drive_gains(np.arange(7.0), np.ones(7))
    d = sim.drive("joint3")
    assert (d.type, d.stiffness, d.max_force, d.target_position) == (fd.DriveType.force, 2.0, 9.0, 0.25)


def test_limit_force_pushes_back(arm):
    """A drive pulling past an upper limit: the limit force pushes towards -q."""
    sim = fd.Simulation(arm, dt=0.01)
    sim.set_joint_limits("joint1", -0.1, 0.1)
    sim.set_drive("joint1", fd.Drive(stiffness=5000.0, damping=100.0, target_position=1.0))
    sim.step(100)
    assert sim.q[0] == pytest.approx(0.1, abs=1e-2)
    assert sim.limit_force[0] < 0.0


def test_scene(arm):
    from conftest import ROOT
    scene = fd.load_scene(str(ROOT / "examples" / "arm7_tgs.yaml"))
    assert scene.options.solver == fd.SolverType.tgs and scene.steps == 360
    sim = fd.make_simulation(scene)
    np.testing.assert_array_equal(sim.q, scene.q0)
    assert sim.drive("joint1").stiffness == 100000.0
    for k in range(3):
        fd.apply_targets(scene, sim, k)
        sim.step()
    assert sim.step_count == 3
