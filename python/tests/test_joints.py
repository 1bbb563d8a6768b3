"""Revolute wrap and mimic joints from Python (issue 17): the gear pair's closed form, the wrap
rule, the URDF gripper's scene rows and the errors."""
import math

import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT


def two_wheels(ia=0.05, ib=0.2):
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("base", "", 1.0, [0, 0, 0], np.eye(3) * 0.01, fd.fixed_joint("fix")))
    b.add_link(fd.make_link("a", "base", 1.0, [0, 0, 0], np.diag([0.6 * ia, 0.6 * ia, ia]),
                            fd.revolute_joint("wheel_a", [0, 0, 1], [0.2, 0, 0])))
    b.add_link(fd.make_link("b", "base", 1.0, [0, 0, 0], np.diag([0.6 * ib, 0.6 * ib, ib]),
                            fd.revolute_joint("wheel_b", [0, 0, 1], [-0.2, 0, 0])))
    return b.build()


def test_gear_pair_shares_the_momentum_as_the_closed_form():
    # a - 2 b = 0 from w_a = 3, w_b = 0: G I_a w_a - I_b w_b is conserved, so
    # w_a = G^2 I_a w0 / (G^2 I_a + I_b) with G = -2.
    sim = fd.Simulation(two_wheels(), dt=0.01)
    sim.add_mimic_joint("wheel_a", "wheel_b", -2.0)
    sim.set_qd([3.0, 0.0])
    sim.step(5)
    wa = 4 * 0.05 * 3.0 / (4 * 0.05 + 0.2)
    assert sim.qd[0] == pytest.approx(wa, abs=1e-12)
    assert sim.qd[1] == pytest.approx(wa / 2, abs=1e-12)
    (row,) = sim.mimic_joints()
    assert (row.follower, row.leader, row.gear_ratio) == (0, 1, -2.0)
    sim.clear_mimic_joints()
    assert sim.mimic_joints() == []


def test_wrapped_wheel_stays_within_two_pi():
    sim = fd.Simulation(two_wheels(), dt=0.01)
    assert sim.revolute_wrap("wheel_a") == "unwrapped"
    sim.set_revolute_wrap("wheel_a", "wrapped")
    sim.set_qd([5.0, 5.0])
    sim.step(200)  # 10 rad: wrapped once, by 4 pi
    assert sim.q[0] == pytest.approx(sim.q[1] - 4 * math.pi, abs=1e-12)
    assert fd.Simulation(two_wheels(), compat="physx").revolute_wrap(0) == "wrapped"


def test_scene_applied_forces_are_constants_or_sines():
    scene = fd.parse_scene("model: slider.urdf\nsteps: 1\n"
                           "applied_force: {slide: {sine: {amplitude: 2, frequency: 0.5}}}\n",
                           str(ROOT / "examples" / "inline.yaml"))
    (sine,) = scene.applied_forces.values()
    assert (sine.amplitude, sine.frequency) == (2.0, 0.5)
    sim = fd.make_simulation(scene)
    fd.apply_targets(scene, sim, 1)  # step 1 starts at t = dt
    assert sim.applied_force[0] == pytest.approx(2 * math.sin(math.pi * scene.options.dt), abs=1e-15)


def test_bad_values_raise_value_error_and_wrong_types_type_error():
    sim = fd.Simulation(two_wheels())
    with pytest.raises(ValueError, match="cannot mimic itself"):
        sim.add_mimic_joint("wheel_a", "wheel_a", 1.0)
    with pytest.raises(ValueError, match="gear_ratio = 0"):
        sim.add_mimic_joint("wheel_a", "wheel_b", 0.0)
    with pytest.raises(ValueError, match="nope"):
        sim.add_mimic_joint("nope", "wheel_b", 1.0)
    sim.add_mimic_joint("wheel_a", "wheel_b", 1.0)
    with pytest.raises(ValueError, match="closes a cycle"):
        sim.add_mimic_joint("wheel_b", "wheel_a", 1.0)
    assert len(sim.mimic_joints()) == 1
    with pytest.raises(ValueError, match="wrapped or unwrapped"):
        sim.set_revolute_wrap("wheel_a", "wrap")
    with pytest.raises(TypeError):
        sim.set_revolute_wrap("wheel_a", 1)


def test_urdf_gripper_scene_holds_its_mimic_rows():
    scene = fd.parse_scene("model: ../tests/data/mimic_gripper.urdf\nsteps: 50\n"
                           "drives: {left_finger: {type: force, stiffness: 400, damping: 20, "
                           "target_position: 0.03}}\n"
                           "solver: {type: pgs, position_iterations: 48, velocity_iterations: 4}\n",
                           str(ROOT / "examples" / "inline.yaml"))
    assert [(m.gear_ratio, m.offset) for m in scene.mimic] == [(1.0, 0.0), (-12.5, 0.1)]
    assert scene.applied_forces == {}
    sim = fd.make_simulation(scene)
    for k in range(scene.steps):
        fd.apply_targets(scene, sim, k)
        sim.step()
    left, right, knuckle = (sim.q[sim.model.dof_index(j)]
                            for j in ("left_finger", "right_finger", "knuckle"))
    assert left == pytest.approx(0.03, abs=3e-3)
    assert right == pytest.approx(-left, abs=1e-9)
    assert knuckle == pytest.approx(12.5 * left - 0.1, abs=1e-9)
