"""fd.Settings, one value for every setting: what the importers give (robot_settings,
scene_settings), what Simulation(model, settings) and Batch(model, count, settings) take, and the
errors. The expectations are the files' own values."""
import pathlib

import numpy as np
import pytest

import featherdrive as fd

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_urdf_settings_carry_its_limits_and_mimic_rows():
    # tests/data/branches.urdf: "left" (prismatic, [0, 0.1], velocity 0.5) mimics "right1" with
    # multiplier -0.5, offset 0.01: the row left + 0.5 right1 - 0.01 = 0.
    robot = fd.load_urdf(ROOT / "tests" / "data" / "branches.urdf")
    s = fd.robot_settings(robot, fd.SimulationOptions(dt=0.002))
    left = robot.model.dof_index("left")
    assert s.options.dt == 0.002
    assert s.lower_limit[left] == 0.0 and s.upper_limit[left] == 0.1
    assert s.max_joint_velocity[left] == 0.5
    (row,) = s.mimic_joints
    assert (row.follower, row.gear_ratio, row.offset) == (left, 0.5, -0.01)
    sim = fd.Simulation(robot.model, s)
    assert len(sim.settings.mimic_joints) == 1
    batch = fd.Batch(robot.model, 3, s)
    assert batch.sim(2).options.dt == 0.002


def test_mjcf_settings_carry_its_actuators():
    xml = """<mujoco><worldbody>
      <body name="a"><joint name="hinge" axis="0 1 0"/><geom size=".1"/></body>
    </worldbody><actuator>
      <position name="p" joint="hinge" kp="50" gear="2"/>
      <velocity name="v" joint="hinge" kv="4" gear="2"/>
    </actuator></mujoco>"""
    robot = fd.parse_mjcf(xml, "pd.xml")
    s = fd.robot_settings(robot)
    # kp gear^2 and kv gear^2 (docs/mujoco_bridge.md).
    assert (s.actuators[0].stiffness, s.actuators[0].damping) == (200.0, 16.0)
    assert fd.Simulation(robot.model, s).actuator(0).stiffness == 200.0


def test_scene_settings_are_its_values():
    scene = fd.parse_scene("""model: slider.urdf
dt: 0.01
steps: 10
drives:
  slide: {type: acceleration, stiffness: 40, damping: 3, delay: 2, target_position: 0.2}
joints:
  slide: {lower: -0.5, upper: 0.25, max_velocity: 1.5}
""", pathlib.Path(fd.example_path("slider.urdf")).parent / "inline.yaml")
    s = fd.scene_settings(scene)
    assert s.options.dt == 0.01
    assert (s.drives[0].stiffness, s.drives[0].damping) == (40.0, 3.0)
    assert s.drive_delay == [2]
    assert (s.lower_limit[0], s.upper_limit[0], s.max_joint_velocity[0]) == (-0.5, 0.25, 1.5)


def test_edits_and_set_settings():
    model = fd.load_urdf(fd.example_path("arm7.urdf")).model
    sim = fd.Simulation(model)
    s = sim.settings
    s.max_joint_velocity[2] = 0.75  # a view into the value
    drives = s.drives               # a copy: edit it, then give it back
    drives[1] = fd.Drive("force", stiffness=100.0, damping=5.0)
    s.drives = drives
    s.revolute_wrap = ["wrapped"] * model.nv
    sim.set_settings(s)
    assert sim.max_joint_velocity(2) == 0.75
    assert sim.drive(1).stiffness == 100.0
    assert sim.revolute_wrap(0) == "wrapped"
    # The simulation's settings are not changed through a copy read earlier.
    s.max_joint_velocity[2] = 0.5
    assert sim.max_joint_velocity(2) == 0.75


def test_bad_settings_raise_value_error_and_change_nothing():
    arm = fd.load_urdf(fd.example_path("arm7.urdf")).model
    slider = fd.load_urdf(fd.example_path("slider.urdf")).model
    with pytest.raises(ValueError, match="drives"):
        fd.Simulation(slider, fd.Settings.defaults(arm))
    with pytest.raises(ValueError):
        fd.Batch(slider, 2, fd.Settings.defaults(arm))
    sim = fd.Simulation(arm)
    s = sim.settings
    s.max_joint_velocity[0] = -1.0
    with pytest.raises(ValueError, match="max_velocity|max_joint_velocity"):
        sim.set_settings(s)
    assert sim.max_joint_velocity(0) == fd.Simulation(arm).max_joint_velocity(0)
    with pytest.raises(ValueError):
        s.revolute_wrap = ["sometimes"] * arm.nv
    assert not np.isnan(sim.settings.lower_limit).any()
