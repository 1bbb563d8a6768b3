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
    """q (+) s dq on the joints' manifolds (revolute: q + s dq; ball: Q exp; floating: p + s R v,
    Q exp)."""
    out = np.array(q, dtype=float)
    for link in model.links:
        i, k = link.q_index, link.v_index
        if link.joint_type in (fd.JointType.revolute, fd.JointType.prismatic):
            out[i] += s * dq[k]
        elif link.joint_type == fd.JointType.spherical:  # body-frame angular velocity
            out[i:i + 4] = quat_mul(q[i:i + 4], quat_exp(s * np.asarray(dq[k:k + 3])))
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


# ---- forward dynamics, MuJoCo's qfrc_bias, Batch's per-environment queries ----------------------

def inertia(rng):
    """A random symmetric positive definite inertia that meets the triangle inequality."""
    R = quat_matrix(*(lambda v: v / np.linalg.norm(v))(rng.standard_normal(4)))
    return R @ np.diag(rng.uniform(0.03, 0.05, 3)) @ R.T


def ball_on_floating_base():
    """A floating base, a ball joint and a hinge after it: every kind of multi-dof joint."""
    rng = np.random.default_rng(11)
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("base", "", 2.0, [0.03, -0.02, 0.05], inertia(rng),
                            fd.floating_joint("root")))
    b.add_link(fd.make_link("upper", "base", 1.0, [0.0, 0.02, 0.15], inertia(rng),
                            fd.spherical_joint("ball", [0.1, 0.0, 0.2], [0.3, 0.0, 0.2])))
    b.add_link(fd.make_link("lower", "upper", 0.7, [0.01, 0.0, 0.1], inertia(rng),
                            fd.revolute_joint("hinge", [0.0, 1.0, 0.0], [0.0, 0.0, 0.3])))
    return b.build()


@pytest.fixture(scope="module", params=["arm fixed", "arm floating", "wrist ball", "ball floating"])
def any_robot(request):
    if request.param == "ball floating":
        return ball_on_floating_base()
    if request.param == "wrist ball":
        return fd.load_urdf(fd.example_path("spherical_wrist.urdf")).model
    return fd.load_urdf(str(ARM), fd.UrdfOptions(fixed_base=request.param == "arm fixed")).model


def unit_state(model, seed):
    """A random q with every quaternion (floating and ball) of unit length, and a random qd."""
    rng = np.random.default_rng(seed)
    q = np.array(model.neutral_configuration()) + 0.5 * rng.standard_normal(model.nq)
    for link in model.links:
        if link.joint_type in (fd.JointType.floating, fd.JointType.spherical):
            i = link.q_index + (3 if link.joint_type == fd.JointType.floating else 0)
            q[i:i + 4] /= np.linalg.norm(q[i:i + 4])
    return q, rng.standard_normal(model.nv)


def test_forward_dynamics_solves_the_mass_matrix_and_bias(any_robot):
    """ABA against CRBA's M and RNEA's b: qdd = M^-1 (tau - b), on the module and a Simulation."""
    model = any_robot
    q, qd = unit_state(model, 21)
    tau = 3.0 * np.random.default_rng(22).standard_normal(model.nv)
    M, b = fd.mass_matrix(model, q), fd.bias_forces(model, q, qd)
    expected = np.linalg.solve(M, tau - b)
    qdd = fd.forward_dynamics(model, q, qd, tau)
    assert qdd.shape == (model.nv,)
    assert np.abs(qdd - expected).max() < 1e-10 * (1 + np.abs(expected).max())
    sim = fd.Simulation(model)
    sim.set_q(q)
    sim.set_qd(qd)
    assert np.array_equal(sim.forward_dynamics(tau), qdd)
    # At rest with tau = g(q) the robot is held: no acceleration.
    held = fd.forward_dynamics(model, q, np.zeros(model.nv), fd.gravity_forces(model, q))
    assert np.abs(held).max() < 1e-10


def test_forward_dynamics_refuses_bad_input(arm):
    q, qd = np.zeros(arm.nq), np.zeros(arm.nv)
    with pytest.raises(ValueError, match=r"tau has shape \(6,\), expected \(7,\)"):
        fd.forward_dynamics(arm, q, qd, np.zeros(6))
    with pytest.raises(ValueError, match=r"tau\[3\] = nan is not finite"):
        fd.forward_dynamics(arm, q, qd, np.array([0, 0, 0, np.nan, 0, 0, 0]))
    with pytest.raises(ValueError, match=r"qd has shape \(8,\), expected \(7,\)"):
        fd.forward_dynamics(arm, q, np.zeros(8), np.zeros(7))
    with pytest.raises(ValueError, match=r"q\[1\] = inf is not finite"):
        fd.forward_dynamics(arm, np.array([0, np.inf, 0, 0, 0, 0, 0]), qd, np.zeros(7))
    with pytest.raises(ValueError, match=r"tau\[0\] = -inf is not finite"):
        fd.Simulation(arm).forward_dynamics(np.full(7, -np.inf))


def mujoco_velocity(R, v):
    """MuJoCo's qvel of a free root at orientation R: [world velocity of the origin; body-frame
    angular velocity], from featherdrive's body-frame v = [w; u] (docs/conventions.md)."""
    return np.concatenate([R @ v[3:6], v[0:3], v[6:]])


def test_mujoco_qfrc_bias_of_a_free_body_is_its_closed_form():
    """One free body, centre of mass at its origin: MuJoCo's qvel has the world velocity of the
    centre, which gravity alone changes, so qfrc_bias = [-m g; w x I w] (Euler's equations);
    featherdrive's bias has m (w x u) in its linear rows instead."""
    rng = np.random.default_rng(5)
    I = inertia(rng)
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("body", "", 1.7, [0, 0, 0], I, fd.floating_joint("root")))
    model = b.build()
    q, v = unit_state(model, 6)
    w = v[:3]
    expected = np.concatenate([-1.7 * np.array(model.gravity), np.cross(w, I @ w)])
    got = fd.mujoco_qfrc_bias(model, q, v)
    assert np.abs(got - expected).max() < 1e-12 * (1 + np.abs(expected).max())
    assert np.abs(fd.bias_forces(model, q, v) - expected).max() > 0.1  # the conventions differ


def test_mujoco_qfrc_bias_balances_motion_in_mujoco_velocities(any_robot):
    """With no joint force, MuJoCo's M_mj qacc + qfrc_bias = 0, qacc the time derivative of
    MuJoCo's qvel along the motion (central differences over +-h of forward dynamics and the
    root's rotation), M_mj = A M A^T the same kinetic energy in qvel. On a fixed base it is
    bias_forces itself."""
    model = any_robot
    q, v = unit_state(model, 31)
    got = fd.mujoco_qfrc_bias(model, q, v)
    if not model.floating_base():
        assert np.array_equal(got, fd.bias_forces(model, q, v))
        return
    a = fd.forward_dynamics(model, q, v, np.zeros(model.nv))
    R, _ = fd.link_pose(model, q, 0)
    h = 1e-5

    def qvel(s):
        return mujoco_velocity(R @ quat_matrix(*quat_exp(s * v[:3])), v + s * a)

    qacc = (qvel(h) - qvel(-h)) / (2 * h)
    A = np.eye(model.nv)
    A[:6, :6] = np.block([[np.zeros((3, 3)), R], [np.eye(3), np.zeros((3, 3))]])
    M_mj = A @ fd.mass_matrix(model, q) @ A.T
    residual = M_mj @ qacc + got
    assert np.abs(residual).max() < 1e-6 * (1 + np.abs(got).max())


def batch_of(model, n=5):
    """n environments at different states; environment 2 a heavier link and 3 more armature
    (their own models)."""
    batch = fd.Batch(model, n)
    states = [unit_state(model, 40 + i) for i in range(n)]
    batch.set_q(np.array([s[0] for s in states]))
    batch.set_qd(np.array([s[1] for s in states]))
    batch.set_link_mass(model.num_links() - 1, [3.0], env_ids=[2])
    return batch


def test_batch_queries_are_each_environments_own(any_robot):
    model = any_robot
    batch = batch_of(model)
    last = model.links[-1].name
    point = [0.02, -0.01, 0.05]
    J = batch.jacobians(last, point)
    J_local = batch.jacobians(last, point, "local")
    M = batch.mass_matrices()
    b = batch.bias_forces()
    R, p = batch.link_poses(last)
    n, nv = len(batch), model.nv
    assert J.shape == (n, 6, nv) and M.shape == (n, nv, nv) and b.shape == (n, nv)
    assert R.shape == (n, 3, 3) and p.shape == (n, 3)
    for i in range(n):
        sim = batch.sim(i)
        assert np.array_equal(J[i], sim.jacobian(last, point))
        assert np.array_equal(J_local[i], sim.jacobian(last, point, "local"))
        assert np.array_equal(M[i], sim.mass_matrix())
        assert np.array_equal(b[i], sim.bias_forces())
        Ri, pi = sim.link_pose(last)
        assert np.array_equal(R[i], Ri) and np.array_equal(p[i], pi)
    assert not np.array_equal(M[2], M[1])  # the heavier link is in environment 2's M
    # The same bits on 1 and 2 threads.
    batch.num_threads = 2
    assert np.array_equal(batch.mass_matrices(), M) and np.array_equal(batch.jacobians(last, point), J)


def test_batch_queries_meet_independent_properties(any_robot):
    """Each environment's M is symmetric positive definite and gives the kinetic energy summed
    over its links (mass and inertia of that environment, velocities of the link centres from
    frame_velocity) plus the armature's; its Jacobian is the central difference of link poses."""
    model = any_robot
    batch = batch_of(model)
    M, (R, _) = batch.mass_matrices(), batch.link_poses(0)
    last = model.links[-1].name
    point = np.array([0.02, -0.01, 0.05])
    J = batch.jacobians(last, point)
    armature = np.array(batch.armature())
    eye = np.eye(model.nv)
    for i in range(len(batch)):
        assert np.abs(M[i] - M[i].T).max() <= 1e-13 * np.abs(M[i]).max()
        assert np.linalg.eigvalsh(M[i]).min() > 0
        sim = batch.sim(i)
        qd = np.array(sim.qd)
        energy = 0.5 * np.sum(armature[i] * qd * qd)
        for l, link in enumerate(model.links):
            mass = batch.link_mass(l)[i]
            inertia_world = (mass / link.mass if link.mass > 0 else 1.0) * np.asarray(
                link.inertia_com)
            Rl, _ = sim.link_pose(l)
            w, v = np.split(sim.frame_velocity(l, link.com), 2)
            energy += 0.5 * mass * v @ v + 0.5 * w @ (Rl @ inertia_world @ Rl.T) @ w
        assert abs(0.5 * qd @ M[i] @ qd - energy) < 1e-12 * (1 + energy), i
        q = np.array(sim.q)
        fd_J = np.column_stack([pose_rate(model, q, eye[k], last, point)
                                for k in range(model.nv)])
        assert rel(J[i], fd_J) < 1e-7, i
    assert np.array_equal(R[:, :, :], np.array([batch.sim(i).link_pose(0)[0]
                                                for i in range(len(batch))]))
