"""A floating root placed in world axes (Simulation.set_base_state, docs/conventions.md): a free
body so placed flies the ballistic arc of the step, p_n = p_0 + n h v_0 + h^2 g n (n + 1) / 2;
base_state reads back what was set; a fixed robot or a zero orientation is a ValueError."""
import numpy as np
import pytest

import featherdrive as fd


def free_box():
    b = fd.ModelBuilder()
    b.set_gravity([0, 0, -9.81])
    b.add_link(fd.make_link("box", "", 2.0, [0, 0, 0], 0.3 * np.eye(3), fd.floating_joint("root")))
    return fd.Simulation(b.build())


def test_a_placed_free_body_flies_the_discrete_ballistic_arc():
    sim = free_box()
    p0, v0 = np.array([0.5, -1.0, 2.0]), np.array([1.0, 0.5, 3.0])
    turn = np.array([np.cos(0.35), 0.0, 0.0, np.sin(0.35)])  # 0.7 rad about z
    sim.set_base_state(position=p0, orientation=turn, linear_velocity=v0)
    base = sim.base_state()
    assert np.allclose(base["position"], p0, atol=1e-15)
    assert abs(abs(base["orientation"] @ turn) - 1.0) < 1e-15
    assert np.allclose(base["linear_velocity"], v0, atol=1e-15)
    h, g = sim.options.dt, np.array([0.0, 0.0, -9.81])
    for n in range(1, 31):
        sim.step()
        expected = p0 + n * h * v0 + h * h * g * n * (n + 1) / 2
        assert np.allclose(sim.base_state()["position"], expected, rtol=0, atol=1e-12)
    # What is not given stays.
    sim.set_base_state(angular_velocity=[0.0, 0.0, 1.0])
    assert np.allclose(sim.base_state()["position"], expected, rtol=0, atol=1e-12)
    assert np.allclose(sim.base_state()["angular_velocity"], [0, 0, 1], atol=1e-15)


def test_bad_input_is_a_value_error():
    sim = free_box()
    with pytest.raises(ValueError, match="has no rotation"):
        sim.set_base_state(orientation=[0, 0, 0, 0])
    with pytest.raises(ValueError, match="base position"):
        sim.set_base_state(position=[1, 2])
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("arm", "", 1.0, [0, 0, 0], np.eye(3), fd.revolute_joint("hinge", [0, 0, 1])))
    fixed = fd.Simulation(b.build())
    with pytest.raises(ValueError, match="no floating root"):
        fixed.set_base_state(position=[0, 0, 1])
    with pytest.raises(ValueError, match="no floating root"):
        fixed.base_state()
