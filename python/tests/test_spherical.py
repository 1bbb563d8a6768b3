"""Spherical joints from Python: PhysX's axis names (docs/math/spherical_joints.md) name the dofs,
take drives and limits, and a bad axis or limit is a ValueError naming it."""
import numpy as np
import pytest

import featherdrive as fd


@pytest.fixture
def wrist():
    return fd.load_urdf(fd.example_path("spherical_wrist.urdf")).model


def test_axes_are_named_and_driven_one_by_one(wrist):
    assert wrist.dof_names == ["shoulder", "wrist:twist", "wrist:swing1", "wrist:swing2"]
    sim = fd.Simulation(wrist)
    sim.set_drive("wrist:swing1", fd.Drive(fd.DriveType.force, 20.0, 1.0))
    assert sim.drive(2).stiffness == 20.0 and sim.drive(1).type == fd.DriveType.none
    # A turn about the joint frame's y axis by 0.4 rad: only swing1's drive pulls, back to 0.
    q = np.array(sim.q)
    q[1:5] = [np.cos(0.2), 0.0, np.sin(0.2), 0.0]
    sim.set_q(q)
    sim.step()
    force = np.array(sim.drive_force)
    assert force[2] < 0 and force[1] == 0 and force[3] == 0


def test_bad_axis_and_limit_are_value_errors(wrist):
    sim = fd.Simulation(wrist)
    with pytest.raises(ValueError, match=r"limits on joint 'wrist:twist': lower = -4 is outside"):
        sim.set_joint_limits("wrist:twist", -4.0, 1.0)
    with pytest.raises(ValueError, match="no joint named 'wrist:tilt'"):
        sim.set_drive("wrist:tilt", fd.Drive(fd.DriveType.force, 1.0, 1.0))
    with pytest.raises(ValueError, match="joint 'wrist' is spherical: name one of its axes"):
        sim.set_drive("wrist", fd.Drive(fd.DriveType.force, 1.0, 1.0))
