"""Explicit actuators (docs/math/explicit_actuators.md) from Python, on the slider of
examples/slider.urdf (2.5 kg along z, limits +-1 m): each kind's applied force against its formula
written out here in numpy, the delay, the Batch binding against single simulations, bad input."""
import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT, hexes, in_lanes

SLIDER = str(ROOT / "examples" / "slider.urdf")
M, H = 2.5, 1.0 / 120.0


@pytest.fixture(scope="module")
def slider():
    """Gravity across the slide: the motion stays clear of the +-1 m limits."""
    return fd.load_urdf(SLIDER, fd.UrdfOptions(gravity=(0.0, -9.81, 0.0))).model


def step_against(sim, force_of, steps=120):
    """Steps sim; each step's actuator force must be force_of(x, v, k) at the step-start state
    and the motion the semi-implicit Euler step under it. Returns how many clipped."""
    x, v = float(sim.q[0]), float(sim.qd[0])
    clipped = 0
    for k in range(steps):
        target = 0.3 * np.sin(0.05 * k)
        sim.set_drive_target("slide", target, 0.0)
        force, demand = force_of(x, v, target)
        clipped += force != demand
        sim.step()
        assert sim.actuator_force[0] == pytest.approx(force, abs=1e-12 * (1 + abs(force)))
        v += H * force / M
        x += H * v
        assert sim.qd[0] == pytest.approx(v, abs=1e-12)
        assert sim.q[0] == pytest.approx(x, abs=1e-12)
    return clipped


def test_ideal_pd_is_the_clipped_pd_law(slider):
    sim = fd.Simulation(slider, dt=H)
    sim.set_actuator("slide", fd.IdealPD(stiffness=400.0, damping=10.0, effort_limit=35.0))
    sim.set_actuator_feedforward("slide", 1.5)

    def force(x, v, target):
        demand = 400.0 * (target - x) + 10.0 * (0.0 - v) + 1.5
        return float(np.clip(demand, -35.0, 35.0)), demand

    clipped = step_against(sim, force)
    assert 5 < clipped < 115
    assert sim.drive_force[0] == 0.0


def test_dc_motor_follows_its_torque_speed_line(slider):
    # S = 40, v_max = 2, E = 30: corner speed 2 (1 + 30 / 40) = 3.5.
    motor = fd.DCMotor(stiffness=1e6, saturation_effort=40.0, velocity_limit=2.0,
                       effort_limit=30.0)
    for v, high in [(0.0, 30.0), (0.5, 30.0), (1.0, 20.0), (2.0, 0.0), (3.0, -20.0),
                    (3.5, -30.0), (9.0, -30.0), (-1.0, 30.0)]:
        sim = fd.Simulation(slider, dt=H)
        sim.set_actuator("slide", motor)
        sim.set_qd([v])
        sim.set_drive_target("slide", 0.5, v)  # a demand far above any bound
        sim.step()
        assert sim.actuator_force[0] == high, v


def test_remotized_interpolates_its_table(slider):
    table = np.array([[-0.5, 4.0], [0.0, 20.0], [0.5, 8.0]])
    sim = fd.Simulation(slider, dt=H)
    sim.set_actuator("slide", fd.RemotizedPD(stiffness=300.0, damping=5.0, lookup=table))
    assert np.array_equal(sim.actuator("slide").lookup, table)

    def force(x, v, target):
        demand = 300.0 * (target - x) - 5.0 * v
        limit = np.interp(x, table[:, 0], table[:, 1])  # holds the end values beyond the table
        return float(np.clip(demand, -limit, limit)), demand

    assert step_against(sim, force) > 5


def test_delay_shifts_the_commands_by_exactly_d_steps(slider):
    commands = np.sin(0.9 * np.arange(30))
    for d in (0, 2, 5):
        sim = fd.Simulation(slider, dt=H)
        sim.set_actuator("slide", fd.IdealPD(delay=d))
        seen = []
        for c in commands:
            sim.set_actuator_feedforward("slide", c)
            sim.step()
            seen.append(sim.actuator_force[0])
        expected = [commands[max(k - d, 0)] for k in range(30)]
        assert hexes(seen) == hexes(expected), d


def test_actuator_force_is_a_read_only_view(slider):
    sim = fd.Simulation(slider, dt=H)
    view = sim.actuator_force
    sim.set_actuator(0, fd.ExplicitActuator("ideal_pd", stiffness=0.0))
    sim.set_actuator_feedforward(0, 2.0)
    sim.step()
    assert view[0] == 2.0
    assert not view.flags.writeable


@pytest.mark.parametrize("integration", ["explicit", "implicit"])
@pytest.mark.parametrize("lanes", [False, True])
def test_batch_set_actuator_equals_single_simulations(slider, lanes, integration):
    """Without SIMD lanes each environment is its Simulation bit for bit; in them (the actuators
    a control stage before the lane step, an implicit one's law the dof's row there) within
    1e-12, another operation order."""
    proto = fd.Simulation(slider, dt=H)
    batch = fd.Batch(proto, 3)
    batch.lanes = lanes
    motor = fd.DCMotor(stiffness=800.0, damping=20.0, saturation_effort=60.0,
                       velocity_limit=1.5, delay=2, integration=integration)
    batch.set_actuator("slide", motor, env_ids=np.array([0, 2]))
    singles = [fd.Simulation(slider, dt=H) for _ in range(3)]
    for i in (0, 2):
        singles[i].set_actuator("slide", motor)
    for k in range(40):
        for i in (0, 2):  # copy 1 has neither actuator nor drive: no target
            for s in (batch.sim(i), singles[i]):
                s.set_drive_target("slide", 0.2 * np.sin(0.1 * k + i), 0.0)
        batch.step()
        for s in singles:
            s.step()
    assert in_lanes(batch.step_path) == lanes, batch.step_path
    for i in range(3):
        if lanes:
            assert np.abs(batch.sim(i).q - singles[i].q).max() <= 1e-12
            assert np.abs(batch.sim(i).actuator_force - singles[i].actuator_force).max() <= 1e-12
        else:
            assert hexes(batch.sim(i).q) == hexes(singles[i].q)
            assert hexes(batch.sim(i).actuator_force) == hexes(singles[i].actuator_force)
    assert batch.sim(1).actuator_force[0] == 0.0
    assert batch.sim(2).actuator("slide").kind == fd.ActuatorKind.dc_motor


def test_bad_input(slider):
    sim = fd.Simulation(slider, dt=H)
    sim.set_drive("slide", fd.Drive("force", stiffness=10.0))
    with pytest.raises(ValueError, match="joint 'slide' has a force drive: an explicit ideal_pd"):
        sim.set_actuator("slide", fd.IdealPD(stiffness=1.0))
    sim.set_drive("slide", fd.Drive("none"))
    with pytest.raises(ValueError, match="stiffness = -1 must be finite and >= 0"):
        sim.set_actuator("slide", fd.IdealPD(stiffness=-1.0))
    with pytest.raises(ValueError, match="actuator kind = 'servo'"):
        fd.ExplicitActuator("servo")
    with pytest.raises(TypeError):
        fd.ExplicitActuator(3)
    with pytest.raises(TypeError):
        fd.IdealPD(1.0)  # keyword arguments only
    with pytest.raises(ValueError, match=r"lookup has shape \(3,\), expected \(n, 2\)"):
        fd.RemotizedPD(lookup=[0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="delay = -1 is out of range"):
        fd.IdealPD(delay=-1)
    with pytest.raises(ValueError, match="has no explicit actuator"):
        sim.set_actuator_feedforward("slide", 1.0)
    sim.set_actuator("slide", fd.IdealPD(stiffness=1.0))
    with pytest.raises(ValueError, match="joint 'slide' has an explicit actuator"):
        sim.set_drive("slide", fd.Drive("force", stiffness=10.0))
    batch = fd.Batch(fd.Simulation(slider, dt=H), 2)
    batch.sim(1).set_drive("slide", fd.Drive("force", stiffness=10.0))
    with pytest.raises(ValueError, match="has a force drive"):
        batch.set_actuator("slide", fd.IdealPD(stiffness=1.0))
    assert not batch.sim(0).actuator("slide").kind == fd.ActuatorKind.ideal_pd  # nothing set
    with pytest.raises(ValueError, match=r"environment index 2 is out of range"):
        batch.set_actuator("slide", fd.IdealPD(), env_ids=[2])


def test_urdf_effort_option(slider):
    robot = fd.load_urdf(SLIDER, fd.UrdfOptions(effort="effort_limit"))
    sim = fd.Simulation(robot.model, dt=H)
    sim.set_actuator("slide", fd.IdealPD(stiffness=5.0))
    fd.apply_urdf_effort_limits(robot, sim)
    assert sim.actuator("slide").effort_limit == 200.0
    with pytest.raises(ValueError, match="effort = 'sim'"):
        fd.UrdfOptions(effort="sim")


def test_implicit_integration_is_implicit_euler_of_the_law(slider):
    """integration='implicit' (docs/math/implicit_actuators.md eq. I3): each step is implicit
    Euler of M x'' = kp (x* - x) + kd (v* - v) + ff, at gains where the explicit law diverges."""
    h, kp, kd, ff = 0.02, 5e4, 40.0, 3.0  # kp h^2 / M = 8: beyond the explicit law's 4
    actuator = fd.IdealPD(stiffness=kp, damping=kd, integration="implicit")
    assert actuator.integration == fd.ActuatorIntegration.implicit
    assert fd.IdealPD().integration == fd.ActuatorIntegration.explicit  # the default
    assert "integration='implicit'" in repr(actuator)
    sim = fd.Simulation(slider, dt=h)
    sim.set_actuator("slide", actuator)
    sim.set_actuator_feedforward("slide", ff)
    x, v = 0.0, 0.0
    for k in range(50):
        target, target_v = 0.3 * np.sin(0.2 * k), 0.1
        sim.set_drive_target("slide", target, target_v)
        sim.step()
        v = (M * v + h * (kp * (target - x) + kd * target_v + ff)) / (M + h * kd + h * h * kp)
        x += h * v
        assert sim.q[0] == pytest.approx(x, rel=1e-12, abs=1e-12)
        assert sim.qd[0] == pytest.approx(v, rel=1e-12, abs=1e-12)
        assert sim.actuator_force[0] == pytest.approx(kp * (target - x) + kd * (target_v - v) + ff,
                                                      rel=1e-9, abs=1e-9)
        assert sim.drive_force[0] == 0.0
    explicit = fd.Simulation(slider, dt=h)
    explicit.set_actuator("slide", fd.IdealPD(stiffness=kp, damping=kd))
    explicit.set_drive_target("slide", 0.3, 0.0)
    explicit.step(200)
    # The explicit law never settles: it rings at the slider's 10 m/s velocity limit.
    assert abs(explicit.q[0] - 0.3) > 0.05 and abs(explicit.qd[0]) > 1.0


def test_integration_setting_and_bad_values():
    a = fd.DCMotor(saturation_effort=5.0, velocity_limit=1.0, integration=fd.ActuatorIntegration.implicit)
    assert a.integration == fd.ActuatorIntegration.implicit
    a.integration = "explicit"
    assert a.integration == fd.ActuatorIntegration.explicit
    assert fd.RemotizedPD(lookup=[[0.0, 1.0]], integration="implicit").integration == \
        fd.ActuatorIntegration.implicit
    with pytest.raises(ValueError, match="integration = 'semi': must be 'explicit' or 'implicit'"):
        fd.IdealPD(integration="semi")
    with pytest.raises(TypeError):
        a.integration = 1


def test_batch_with_implicit_actuators_equals_single_simulations(slider):
    proto = fd.Simulation(slider, dt=H)
    batch = fd.Batch(proto, 2)
    motor = fd.DCMotor(stiffness=5e5, damping=20.0, saturation_effort=60.0, velocity_limit=1.5,
                       delay=1, integration="implicit")
    batch.set_actuator("slide", motor)
    single = fd.Simulation(slider, dt=H)
    single.set_actuator("slide", motor)
    for k in range(40):
        for s in (batch.sim(0), batch.sim(1), single):
            s.set_drive_target("slide", 0.2 * np.sin(0.1 * k), 0.0)
        batch.step()
        single.step()
    for i in range(2):
        assert hexes(batch.sim(i).q) == hexes(single.q)
        assert hexes(batch.sim(i).actuator_force) == hexes(single.actuator_force)
    assert batch.sim(1).actuator("slide").integration == fd.ActuatorIntegration.implicit
