"""Spherical joints from Python: PhysX's axis names (docs/math/spherical_joints.md) name the dofs,
take drives and limits, and a bad axis or limit is a ValueError naming it."""
import numpy as np
import pytest

import featherdrive as fd
from conftest import ROOT

WRIST_SCENE = str(ROOT / "examples" / "spherical_wrist.yaml")


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


# ---- every face reads a dof's position through fd.dof_positions (model/dof_position.hpp) --------

def _rotation_vector(qwxyz):
    """PhysX's positions of a spherical joint, written out here: the rotation vector angle * axis
    of the quaternion, angle in [0, pi] (the hemisphere w >= 0)."""
    w, v = qwxyz[0], np.asarray(qwxyz[1:], dtype=float)
    if w < 0:
        w, v = -w, -v
    s = np.linalg.norm(v)
    return np.zeros(3) if s == 0 else 2.0 * np.arctan2(s, w) * v / s


def test_dof_positions_on_a_ball_joint_and_a_floating_base():
    urdf = ROOT / "tests" / "data" / "spherical_floating.urdf"
    model = fd.load_urdf(urdf, fd.UrdfOptions(False)).model
    assert model.floating_base() and model.nv == 10 and model.nq == 12
    theta = np.array([0.3, -0.2, 0.5])
    angle = np.linalg.norm(theta)
    Q = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * theta / angle])
    wrist = model.links[model.joint_link_index("wrist")]
    shoulder = model.links[model.joint_link_index("shoulder")]
    q = np.array(model.neutral_configuration())
    q[:7] = [1.0, 2.0, 3.0, 0.5, 0.5, 0.5, 0.5]  # the root's pose: no dof position
    q[shoulder.q_index] = 0.7
    for sign in (1.0, -1.0):  # Q and -Q are one rotation
        q[wrist.q_index:wrist.q_index + 4] = sign * Q
        dofs = [d for d in range(model.nv) if fd.has_dof_position(model, d)]
        assert [model.dof_names[d] for d in dofs] == ["shoulder", "wrist:twist", "wrist:swing1",
                                                      "wrist:swing2"]
        np.testing.assert_allclose(fd.dof_positions(model, q), [0.7, *theta], rtol=0, atol=1e-15)
    # The inverse poses the joint at exp(theta), as a scene's initial q does.
    back = fd.set_dof_positions(model, model.neutral_configuration(), dofs, [0.7, *theta])
    np.testing.assert_allclose(back[wrist.q_index:wrist.q_index + 4], Q, atol=1e-15)
    with pytest.raises(ValueError, match=r"is a floating root's"):
        fd.dof_positions(model, q, [0])
    with pytest.raises(ValueError, match=r"q has shape \(3,\)"):
        fd.dof_positions(model, [1.0, 2.0, 3.0])


def test_sweep_objective_is_the_axis_position_error():
    """sweep's RMS of a spherical axis is that of target - PhysX's position (a quaternion entry
    before), from a step-by-step run and the rotation vector above."""
    import featherdrive_sweep
    path = WRIST_SCENE
    scene = fd.load_scene(path)
    result = featherdrive_sweep.sweep(path, "stiffness=20", joint="wrist:twist", num_threads=1)
    sim = fd.make_simulation(scene)
    link = scene.model.links[scene.model.joint_link_index("wrist")]
    specs = {d.joint: d for d in scene.drives}
    squares = {j: 0.0 for j in result.joints}
    for k in range(scene.steps):
        fd.apply_targets(scene, sim, k)
        sim.step()
        theta = _rotation_vector(np.array(sim.q)[link.q_index:link.q_index + 4])
        t = (k + 1) * scene.options.dt
        for j in result.joints:
            position = sim.q[0] if j == "shoulder" else theta[["twist", "swing1", "swing2"].index(
                j.split(":")[1])]
            squares[j] += (specs[j].target_at(t)[0] - position) ** 2
    expected = [np.sqrt(squares[j] / scene.steps) for j in result.joints]
    np.testing.assert_allclose(result.rms[0], expected, rtol=1e-12)
    assert abs(expected[result.joints.index("wrist:twist")] - 0.0948) < 5e-4  # not 0.55 (w)


def test_view_curves_and_csv_poses_of_spherical_axes(tmp_path):
    """The viewer's curves of the three axes are the rotation vector of the run's quaternions,
    and a CSV of those positions (written here) poses the wrist with the run's rotation."""
    import featherdrive_view as view
    scene = fd.load_scene(WRIST_SCENE)
    sim = fd.make_simulation(scene)
    run = view._run_simulation(fd, sim, 30)
    data = view._page_data(fd, run, scene.robot, None, {}, "t", None)
    link = scene.model.links[scene.model.joint_link_index("wrist")]
    theta = np.array([_rotation_vector(q[link.q_index:link.q_index + 4]) for q in run.q])
    curves = {j["name"]: j for j in data["joints"]}
    for k, axis in enumerate(("twist", "swing1", "swing2")):
        joint = curves[f"wrist:{axis}"]
        np.testing.assert_allclose(joint["q"], theta[:, k], atol=1e-9)
        assert joint["link"] == "hand" and joint["axis"] == list(np.eye(3)[k])
        assert joint["force"] is not None  # driven: the force marker is coloured
    csv = tmp_path / "run.csv"
    rows = ["step,t,q:shoulder,q:wrist:twist,q:wrist:swing1,q:wrist:swing2"]
    for i, q in enumerate(run.q):
        rows.append(",".join(repr(float(x)) for x in [i, run.times[i], q[0], *theta[i]]))
    csv.write_text("\n".join(rows) + "\n")
    read = view._read_csv(fd, scene, str(csv))
    quats = read.q[:, link.q_index:link.q_index + 4]
    signs = np.sign(np.sum(quats * run.q[:, link.q_index:link.q_index + 4], axis=1))
    np.testing.assert_allclose(quats * signs[:, None], run.q[:, link.q_index:link.q_index + 4],
                               atol=1e-12)
