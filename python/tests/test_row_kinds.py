"""Row kinds from Python (issue 32): the joint spring by name on Simulation, Batch, Settings and
an MJCF robot, against implicit-Euler steps written here and the scalar step; the errors."""
import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT

CHEETAH = ROOT / "tests" / "fuzz" / "corpus" / "mjcf" / "half_cheetah.xml"


def slider(mass):
    b = fd.ModelBuilder()
    b.set_gravity([0, 0, 0])
    b.add_link(fd.make_link("base", "", 1.0, [0, 0, 0], np.eye(3), fd.fixed_joint("fix")))
    b.add_link(fd.make_link("cart", "base", mass, [0, 0, 0], np.eye(3) * 0.01,
                            fd.prismatic_joint("slide", [1, 0, 0])))
    return b.build()


def test_the_kinds_and_their_fields_are_listed():
    kinds = {k["name"]: k for k in fd.row_kinds()}
    spring = kinds["joint_spring"]
    assert spring["force"] == "spring_force"
    assert [f["name"] for f in spring["fields"]] == ["stiffness", "damping", "reference"]
    assert all(f["default"] == 0.0 for f in spring["fields"])


def test_a_spring_is_one_implicit_euler_step_per_step():
    m, dt, k, c, xs = 1.5, 0.01, 600.0, 4.0, 0.25
    sim = fd.Simulation(slider(m), dt=dt, position_iterations=4, velocity_iterations=0)
    sim.set_row_parameters("joint_spring", "slide", stiffness=k, damping=c, reference=xs)
    assert sim.row_parameters("joint_spring", "slide") == {
        "stiffness": k, "damping": c, "reference": xs}
    x, v = 0.0, 0.0
    for _ in range(100):
        sim.step()
        v1 = (m * v - dt * k * (x - xs)) / (m + dt * c + dt * dt * k)
        force = m * (v1 - v) / dt
        x, v = x + dt * v1, v1
        assert sim.q[0] == pytest.approx(x, abs=1e-12)
        assert sim.qd[0] == pytest.approx(v, abs=1e-12)
        assert sim.row_force("joint_spring")[0] == pytest.approx(force, rel=1e-9, abs=1e-9)
    # A field not given keeps its value.
    sim.set_row_parameters("joint_spring", "slide", damping=0.0)
    assert sim.row_parameters("joint_spring", "slide") == {
        "stiffness": k, "damping": 0.0, "reference": xs}


def test_bad_row_settings_are_value_errors():
    sim = fd.Simulation(slider(1.0))
    with pytest.raises(ValueError, match=r"unknown row kind 'spring' \(row kinds: joint_spring\)"):
        sim.set_row_parameters("spring", "slide", stiffness=1.0)
    with pytest.raises(ValueError, match=r"joint_spring has no field 'stifness' \(its fields: "
                                         r"stiffness, damping, reference\)"):
        sim.set_row_parameters("joint_spring", "slide", stifness=1.0)
    with pytest.raises(ValueError, match=r"joint spring of joint 'slide': stiffness = -1 must be "
                                         r"finite and >= 0"):
        sim.set_row_parameters("joint_spring", "slide", stiffness=-1.0)
    with pytest.raises(ValueError, match=r"joint_spring.reference = 'up' is not a number"):
        sim.set_row_parameters("joint_spring", "slide", reference="up")
    assert sim.row_parameters("joint_spring", "slide")["stiffness"] == 0.0


def test_batch_springs_per_environment_match_each_simulation():
    model = fd.load_urdf(str(ROOT / "examples" / "arm7.urdf")).model
    proto = fd.Simulation(model, dt=0.005)
    fd.set_drive_gains(proto, np.full(model.nv, 80.0), np.full(model.nv, 4.0))
    batch = fd.Batch(proto, 4)
    k = np.array([[0.0] * model.nv, [50.0] * model.nv, [200.0] * model.nv, [400.0] * model.nv])
    batch.set_row_parameter("joint_spring", "stiffness", k)
    batch.set_row_parameter("joint_spring", "reference", 0.3, env_ids=[2, 3])
    assert np.array_equal(batch.row_parameter("joint_spring", "stiffness"), k)
    alone = []
    for e in range(4):
        s = fd.Simulation(model, dt=0.005)
        fd.set_drive_gains(s, np.full(model.nv, 80.0), np.full(model.nv, 4.0))
        for j in range(model.nv):
            s.set_row_parameters("joint_spring", j, stiffness=k[e, j],
                                 reference=0.3 if e >= 2 else 0.0)
        alone.append(s)
    batch.step(200)
    for e, s in enumerate(alone):
        s.step(200)
        assert np.allclose(batch.q[e], s.q, rtol=0, atol=1e-12)
        assert np.allclose(batch.row_force("joint_spring")[e], s.row_force("joint_spring"),
                           rtol=1e-12, atol=1e-9)
    assert np.all(batch.row_force("joint_spring")[0] == 0.0)
    assert np.any(batch.row_force("joint_spring")[3] != 0.0)


def test_settings_value_carries_the_row_parameters():
    model = slider(2.0)
    settings = fd.Settings.defaults(model)
    assert settings.row_parameters.shape == (1, 3)
    settings.row_parameters[0, 0] = 75.0
    sim = fd.Simulation(model, settings)
    assert sim.row_parameters("joint_spring", "slide")["stiffness"] == 75.0
    settings.row_parameters[0, 0] = -1.0
    with pytest.raises(ValueError, match="stiffness = -1"):
        settings.validate(model)


def test_mjcf_stiffness_becomes_the_joint_spring():
    robot = fd.load_mjcf(str(CHEETAH))
    assert any("joint stiffness becomes a joint spring" in w for w in robot.warnings)
    sim = fd.Simulation(robot.model, fd.robot_settings(robot))
    # half_cheetah.xml: bthigh stiffness 240, ffoot 60; springref 0.
    assert sim.row_parameters("joint_spring", "bthigh") == {
        "stiffness": 240.0, "damping": 0.0, "reference": 0.0}
    assert sim.row_parameters("joint_spring", "ffoot")["stiffness"] == 60.0
    assert sim.row_parameters("joint_spring", "rootz")["stiffness"] == 0.0


def test_the_joint_accessor_reads_and_writes_row_kinds():
    sim = fd.Simulation(slider(1.0), dt=0.01)
    joint = sim.joint("slide")
    joint.set_row_parameters("joint_spring", stiffness=40.0, reference=-0.1)
    assert joint.row_parameters("joint_spring") == {
        "stiffness": 40.0, "damping": 0.0, "reference": -0.1}
    sim.step()
    # One implicit-Euler step from rest at 0: v1 = h k (x_s - 0) / (m + h^2 k).
    v1 = 0.01 * 40.0 * -0.1 / (1.0 + 1e-4 * 40.0)
    assert joint.row_force("joint_spring") == pytest.approx(v1 / 0.01, rel=1e-12)
    with pytest.raises(ValueError, match="stiffness = -2"):
        joint.set_row_parameters("joint_spring", stiffness=-2.0)
    assert joint.row_parameters("joint_spring")["stiffness"] == 40.0
