"""Kinematics and dynamics through the bindings on the 7-dof arm (fixed and floating base):
Jacobians and dJ/dt qd against numpy central differences of link poses, the centre of mass
against a mass-weighted sum, the mass matrix symmetric positive definite, inverse dynamics
inverted by M and the bias forces, and the Simulation methods equal to the module functions."""
import numpy as np
import pytest

import featherdrive as fd

from conftest import ARM

H = 1e-5  # central differences


@pytest.fixture(scope="module", params=[True, False], ids=["fixed", "floating"])
def robot(request):
    return fd.load_urdf(str(ARM), fd.UrdfOptions(fixed_base=request.param)).model


def state(model, seed):
    rng = np.random.default_rng(seed)
    q = np.array(model.neutral_configuration())
    q += 0.5 * rng.standard_normal(model.nq)
    for link in model.links:  # unit quaternions
        if link.joint_type == fd.JointType.floating:
            quat = slice(link.q_index + 3, link.q_index + 7)
            q[quat] /= np.linalg.norm(q[quat])
    return q, rng.standard_normal(model.nv)


def integrate(model, q, dq, s):
    """q (+) s dq on the joints' manifolds (revolute: q + s dq; floating: p + s R v, Q exp)."""
    out = np.array(q, dtype=float)
    for link in model.links:
        i, k = link.q_index, link.v_index
        if link.joint_type in (fd.JointType.revolute, fd.JointType.prismatic):
            out[i] += s * dq[k]
        elif link.joint_type == fd.JointType.floating:
            w, x, y, z = q[i + 3:i + 7]
            R = quat_matrix(w, x, y, z)
            out[i:i + 3] += s * R @ dq[k + 3:k + 6]
            out[i + 3:i + 7] = quat_mul(q[i + 3:i + 7], quat_exp(s * np.asarray(dq[k:k + 3])))
    return out


def quat_matrix(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def quat_exp(phi):
    angle = np.linalg.norm(phi)
    if angle == 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * phi / angle])


def rotation_vector(R):
    """The axis * angle of a small rotation R."""
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return axis * (0.5 if angle < 1e-12 else angle / (2 * np.sin(angle)))


def pose_rate(model, q, dq, link, point):
    """World-aligned [omega; point velocity] along dq by central differences of link_pose."""
    Rp, pp = fd.link_pose(model, integrate(model, q, dq, H), link)
    Rm, pm = fd.link_pose(model, integrate(model, q, dq, -H), link)
    omega = rotation_vector(Rp @ Rm.T) / (2 * H)
    return np.concatenate([omega, (pp + Rp @ point - pm - Rm @ point) / (2 * H)])


def rel(a, b):
    return np.linalg.norm(a - b) / (1 + np.linalg.norm(b))


def test_jacobians_are_derivatives_of_link_poses(robot):
    q, qd = state(robot, 1)
    point = np.array([0.05, -0.02, 0.1])
    eye = np.eye(robot.nv)
    for link in range(robot.num_links()):
        fd_J = np.column_stack([pose_rate(robot, q, eye[k], link, point) for k in range(robot.nv)])
        J = fd.jacobian(robot, q, link, point)
        assert J.shape == (6, robot.nv)
        assert rel(J, fd_J) < 1e-7, link
        R, _ = fd.link_pose(robot, q, link)
        J_local = fd.jacobian(robot, q, link, point, "local")
        assert rel(J_local, np.vstack([R.T @ fd_J[:3], R.T @ fd_J[3:]])) < 1e-7, link
        v = fd.frame_velocity(robot, q, qd, link, point)
        assert np.allclose(v, J @ qd, rtol=0, atol=1e-12 * (1 + np.abs(J).sum()))


def test_jacobian_dot_is_derivative_of_jacobian_times_qd(robot):
    q, qd = state(robot, 2)
    point = np.array([0.0, 0.03, -0.04])
    for frame in ("world_aligned", "local"):
        for link in range(robot.num_links()):
            Jp = fd.jacobian(robot, integrate(robot, q, qd, H), link, point, frame)
            Jm = fd.jacobian(robot, integrate(robot, q, qd, -H), link, point, frame)
            expected = (Jp - Jm) @ qd / (2 * H)
            got = fd.jacobian_dot_times_qd(robot, q, qd, link, point, frame)
            assert rel(got, expected) < 1e-7, (frame, link)


def test_center_of_mass_is_mass_weighted_sum(robot):
    q, qd = state(robot, 3)
    masses = np.array([link.mass for link in robot.links])
    centres = np.array([fd.frame_position(robot, q, i, link.com)
                        for i, link in enumerate(robot.links)])
    com = fd.center_of_mass(robot, q)
    assert np.allclose(com, masses @ centres / masses.sum(), rtol=0, atol=1e-13)
    J = fd.center_of_mass_jacobian(robot, q)
    assert J.shape == (3, robot.nv)
    eye = np.eye(robot.nv)
    fd_J = np.column_stack([(fd.center_of_mass(robot, integrate(robot, q, eye[k], H)) -
                             fd.center_of_mass(robot, integrate(robot, q, eye[k], -H))) / (2 * H)
                            for k in range(robot.nv)])
    assert rel(J, fd_J) < 1e-7
    weighted = sum(m * fd.jacobian(robot, q, i, link.com)[3:]
                   for i, (m, link) in enumerate(zip(masses, robot.links))) / masses.sum()
    assert rel(J, weighted) < 1e-12
    assert np.allclose(fd.center_of_mass_velocity(robot, q, qd), J @ qd, rtol=0, atol=1e-12)


def test_mass_matrix_and_inverse_dynamics(robot):
    q, qd = state(robot, 4)
    M = fd.mass_matrix(robot, q)
    assert M.shape == (robot.nv, robot.nv)
    assert np.array_equal(M, M.T) or np.abs(M - M.T).max() < 1e-13 * np.abs(M).max()
    assert np.linalg.eigvalsh(M).min() > 0
    b = fd.bias_forces(robot, q, qd)
    g = fd.gravity_forces(robot, q)
    qdd = np.random.default_rng(5).standard_normal(robot.nv)
    tau = fd.inverse_dynamics(robot, q, qd, qdd)
    assert rel(tau, M @ qdd + b) < 1e-12  # M qdd + b = tau
    assert rel(fd.inverse_dynamics(robot, q, qd, np.zeros(robot.nv)), b) < 1e-14
    assert rel(fd.bias_forces(robot, q, np.zeros(robot.nv)), g) < 1e-14
    # Round trip: the accelerations back from tau by solving with M.
    assert rel(np.linalg.solve(M, tau - b), qdd) < 1e-10


def test_gravity_is_gradient_of_potential_energy(robot):
    q, _ = state(robot, 6)
    total = sum(link.mass for link in robot.links)
    eye = np.eye(robot.nv)

    def potential(qq):
        return -total * np.dot(np.array(robot.gravity), fd.center_of_mass(robot, qq))

    grad = np.array([(potential(integrate(robot, q, eye[k], H)) -
                      potential(integrate(robot, q, eye[k], -H))) / (2 * H)
                     for k in range(robot.nv)])
    assert rel(fd.gravity_forces(robot, q), grad) < 1e-7


def test_simulation_methods_equal_module_functions(robot):
    q, qd = state(robot, 7)
    sim = fd.Simulation(robot)
    sim.set_q(q)
    sim.set_qd(qd)
    q, qd = np.array(sim.q), np.array(sim.qd)  # normalised as the simulation holds them
    last = robot.links[-1].name
    point = [0.1, 0.0, 0.0]
    assert np.array_equal(sim.jacobian(last, point), fd.jacobian(robot, q, last, point))
    assert np.array_equal(sim.jacobian(last, frame=fd.ReferenceFrame.local),
                          fd.jacobian(robot, q, last, frame="local"))
    assert np.array_equal(sim.jacobian_dot_times_qd(last, point),
                          fd.jacobian_dot_times_qd(robot, q, qd, last, point))
    assert np.array_equal(sim.frame_velocity(last, point, "local"),
                          fd.frame_velocity(robot, q, qd, last, point, "local"))
    assert np.array_equal(sim.frame_position(last, point),
                          fd.frame_position(robot, q, last, point))
    for a, b in zip(sim.link_pose(last), fd.link_pose(robot, q, last)):
        assert np.array_equal(a, b)
    assert np.array_equal(sim.mass_matrix(), fd.mass_matrix(robot, q))
    assert np.array_equal(sim.bias_forces(), fd.bias_forces(robot, q, qd))
    assert np.array_equal(sim.gravity_forces(), fd.gravity_forces(robot, q))
    assert np.array_equal(sim.inverse_dynamics(qd), fd.inverse_dynamics(robot, q, qd, qd))
    assert np.array_equal(sim.center_of_mass(), fd.center_of_mass(robot, q))
    assert np.array_equal(sim.center_of_mass_velocity(), fd.center_of_mass_velocity(robot, q, qd))
    assert np.array_equal(sim.center_of_mass_jacobian(), fd.center_of_mass_jacobian(robot, q))
    # Results are copies: writing to one changes nothing.
    M = sim.mass_matrix()
    M[0, 0] = 1e9
    assert sim.mass_matrix()[0, 0] != 1e9


def test_bad_arguments_are_refused(arm):
    q = np.zeros(arm.nq)
    with pytest.raises(ValueError, match=r"link index 99 is out of range \[0, "):
        fd.jacobian(arm, q, 99)
    with pytest.raises(ValueError, match="no_such_link"):
        fd.link_pose(arm, q, "no_such_link")
    with pytest.raises(ValueError, match=r"q has shape \(3,\), expected \(7,\)"):
        fd.mass_matrix(arm, np.zeros(3))
    bad = q.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match=r"q\[2\] = nan is not finite"):
        fd.center_of_mass(arm, bad)
    with pytest.raises(ValueError, match=r"qd\[0\] = inf is not finite"):
        fd.bias_forces(arm, q, np.full(arm.nv, np.inf))
    with pytest.raises(ValueError, match=r"frame = 'world': must be 'local' or 'world_aligned'"):
        fd.jacobian(arm, q, 0, frame="world")
    with pytest.raises(TypeError):
        fd.jacobian(arm, q, 1.5)
    with pytest.raises(ValueError, match=r"point has shape \(2,\), expected \(3,\)"):
        fd.jacobian(arm, q, 0, [0.0, 1.0])
    with pytest.raises(ValueError, match=r"qdd has shape"):
        fd.inverse_dynamics(arm, q, np.zeros(arm.nv), np.zeros(arm.nv + 1))
