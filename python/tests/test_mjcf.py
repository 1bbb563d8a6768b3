"""fd.load_mjcf: MJCF robots through MuJoCo's compiler, the same robot type as fd.load_urdf.
Expectations come from the file itself, read with xml.etree."""
import math
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import featherdrive as fd

HUMANOID = pathlib.Path("/usr/share/mujoco/model/humanoid/humanoid.xml")


def file_joints():
    """(name, range in degrees) of every <joint> in the file, in document order."""
    root = ET.parse(HUMANOID).getroot()
    return [(j.get("name"), [float(x) for x in j.get("range").split()])
            for j in root.find("worldbody").iter("joint")]


def test_humanoid_loads_as_a_urdf_robot():
    robot = fd.load_mjcf(str(HUMANOID))
    assert isinstance(robot, fd.UrdfRobot)
    joints = file_joints()
    assert robot.joint_order == [name for name, _ in joints]
    model = robot.model
    assert model.nv == len(joints) == 21
    for name, (lower, upper) in joints:  # <compiler> default: degrees
        dof = robot.joint_order.index(name)
        assert model.lower_limit[dof] == pytest.approx(math.radians(lower), abs=1e-15)
        assert model.upper_limit[dof] == pytest.approx(math.radians(upper), abs=1e-15)
    np.testing.assert_array_equal(model.armature, np.full(21, 0.01))  # class "body"
    assert robot.warnings[0] == ("142 pairs of the robot's own geoms collide in MuJoCo; featherdrive's "
                                 "shapes collide with each other only with contact: "
                                 "{self_collision: true} (off by default; parent and child links "
                                 "never)")
    actuators = ET.parse(HUMANOID).getroot().find("actuator")
    gears = {m.get("joint"): float(m.get("gear")) for m in actuators.iter("motor")}
    assert {a.joint: a.gear for a in robot.actuators} == gears
    assert all(a.kind == "motor" for a in robot.actuators)


def test_free_root_and_qpos0():
    robot = fd.load_mjcf(HUMANOID, fixed_base=False)
    assert robot.model.nv == 27 and robot.root_joint == "root"
    np.testing.assert_array_equal(robot.q0[:7], [0, 0, 1.5, 1, 0, 0, 0])  # <body pos="0 0 1.5">


def test_bad_input():
    with pytest.raises(ValueError, match="no_such.xml: cannot open"):
        fd.load_mjcf("no_such.xml")
    with pytest.raises(ValueError, match=r"tendon.xml: <tendon> 'c'"):
        fd.parse_mjcf('<mujoco><worldbody><body><joint/><geom size=".1"/><site name="a"/>'
                      '<site name="b" pos="0 0 1"/></body></worldbody><tendon><spatial name="c">'
                      '<site site="a"/><site site="b"/></spatial></tendon></mujoco>', "tendon.xml")
    with pytest.raises(TypeError):
        fd.load_mjcf(str(HUMANOID), fixed_base="yes")


def test_position_actuator_becomes_an_explicit_pd():
    xml = ('<mujoco><worldbody><body><joint name="j"/><geom size=".1"/></body></worldbody>'
           '<actuator><position joint="j" kp="30" gear="2" forcelimited="true" '
           'forcerange="-5 5"/></actuator></mujoco>')
    robot = fd.parse_mjcf(xml, "pd.xml")
    (a,) = robot.actuators
    assert a.kind == "position" and a.gain == 30 and a.gear == 2
    sim = fd.Simulation(robot.model)
    fd.apply_mjcf_actuators(robot, sim)
    # MuJoCo: joint effort = gear * clip(kp (ctrl - gear q), forcerange).
    assert sim.actuator("j").stiffness == 30 * 2 ** 2
    assert sim.actuator("j").effort_limit == 2 * 5


def test_empty_text_raises_instead_of_ending_the_process():
    # MuJoCo's fatal error on an empty VFS file printed, waited for Enter and exited.
    with pytest.raises(ValueError, match=r"^x\.xml: empty text"):
        fd.parse_mjcf("", "x.xml")
    with pytest.raises(ValueError, match=r"^y\.xml: no root element"):
        fd.parse_mjcf("<!-- nothing -->", "y.xml")


@pytest.mark.parametrize("element, attribute, value", [
    ("geom", "mass", "nan"), ("body", "pos", "0 nan 0"), ("joint", "damping", "-inf")])
def test_non_finite_numbers_name_the_element_and_attribute(element, attribute, value):
    parts = {"body": "", "joint": "", "geom": ' size="0.1"'}
    parts[element] += f' {attribute}="{value}"'
    xml = (f'<mujoco><worldbody><body{parts["body"]}><joint{parts["joint"]}/>'
           f'<geom{parts["geom"]}/></body></worldbody></mujoco>')
    with pytest.raises(ValueError, match=f'^n.xml: line 1: <{element}> {attribute} = "{value}"'):
        fd.parse_mjcf(xml, "n.xml")


def test_input_files_list_the_file_and_its_includes(tmp_path):
    (tmp_path / "arm.xml").write_text(
        '<mujocoinclude><body><joint name="h"/><geom size="0.1"/></body></mujocoinclude>')
    top = tmp_path / "top.xml"
    top.write_text('<mujoco><worldbody><include file="arm.xml"/></worldbody></mujoco>')
    robot = fd.load_mjcf(str(top))
    assert sorted(map(str, robot.input_files)) == sorted([str(top), str(tmp_path / "arm.xml")])
    urdf = pathlib.Path(__file__).resolve().parents[2] / "examples" / "slider.urdf"
    assert [str(p) for p in fd.load_urdf(str(urdf)).input_files] == [str(urdf)]
