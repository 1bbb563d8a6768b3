"""Bad input raises ValueError with a message naming what was wrong."""
import numpy as np
import pytest

import featherdrive as fd


@pytest.fixture
def sim(arm):
    return fd.Simulation(arm, stiffness=100.0, damping=10.0)  # targets need drives


@pytest.mark.parametrize("method, args, message", [
    ("set_q", (np.zeros(3),), r"q has shape \(3,\), expected \(7,\)"),
    ("set_q", (np.zeros((7, 1)),), r"q has shape \(7, 1\), expected \(7,\)"),
    ("set_qd", (np.zeros(8),), r"qd has shape \(8,\), expected \(7,\)"),
    ("set_applied_force", (np.zeros(6),), r"applied_force has shape \(6,\)"),
    ("set_drive_targets", (np.zeros(5), np.zeros(7)), r"positions has shape \(5,\), expected \(7,\)"),
    ("set_drive_targets", (np.zeros(7), np.zeros((2, 7))), r"velocities has shape \(2, 7\)"),
    ("set_drive_gains", (np.zeros(4), np.zeros(7)), r"stiffness has shape \(4,\)"),
    ("set_drive_gains", (np.zeros(7), np.zeros(9)), r"damping has shape \(9,\)"),
])
def test_wrong_shapes(sim, method, args, message):
    with pytest.raises(ValueError, match=message):
        getattr(sim, method)(*args)


@pytest.mark.parametrize("bad, dtype", [
    (np.array(["a"] * 7), "<U1"),
    (np.zeros(7, dtype=complex), "complex128"),
    (np.zeros(7, dtype=bool), "bool"),
    ([None] * 7, "object"),
])
def test_wrong_dtypes(sim, bad, dtype):
    with pytest.raises(ValueError, match=f"positions has dtype {dtype}"):
        sim.set_drive_targets(bad, np.zeros(7))
    with pytest.raises(ValueError, match=f"q has dtype {dtype}"):
        sim.set_q(bad)


def test_other_real_dtypes_are_accepted(sim):
    sim.set_drive_targets(np.arange(7, dtype=np.int32), [0.0] * 7)
    sim.set_q(np.full(7, 0.5, dtype=np.float32))
    assert sim.drive("joint7").target_position == 6.0 and sim.q[6] == 0.5


def test_non_finite_values(sim):
    with pytest.raises(ValueError, match=r"q\[2\] = nan is not finite"):
        sim.set_q([0, 0, np.nan, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="joint3.*target_position = inf"):
        sim.set_drive_targets([0, 0, np.inf, 0, 0, 0, 0])


def test_unknown_joint_names(sim):
    with pytest.raises(ValueError, match="no joint named 'elbow'"):
        sim.set_drive("elbow", fd.Drive(stiffness=1.0))
    with pytest.raises(ValueError, match="no joint named 'wrist'"):
        sim.set_drive_target("wrist", 0.1, 0.0)
    with pytest.raises(ValueError, match="no joint named 'knee'"):
        sim.set_joint_limits("knee", -1.0, 1.0)
    with pytest.raises(ValueError, match=r"dof index 7 is out of range \[0, 7\)"):
        sim.drive(7)
    with pytest.raises(TypeError, match="expected a joint name"):
        sim.drive(1.5)


def test_bad_gains_name_the_joint_and_change_nothing(sim):
    sim.set_drive_gains(np.full(7, 100.0), np.full(7, 10.0))
    kp = np.full(7, 200.0)
    kp[3] = -5.0
    with pytest.raises(ValueError, match=r"dof 3: drive on joint 'joint4': stiffness = -5 must be finite and >= 0"):
        sim.set_drive_gains(kp, np.full(7, 10.0))
    assert [sim.drive(d).stiffness for d in range(7)] == [100.0] * 7
    kd = np.full(7, 10.0)
    kd[6] = np.nan
    with pytest.raises(ValueError, match="joint 'joint7': damping = nan"):
        sim.set_drive_gains(np.full(7, 1.0), kd)
    with pytest.raises(ValueError, match="drive on joint 'joint2': stiffness = -1"):
        sim.set_drive("joint2", fd.Drive(stiffness=-1.0))
    with pytest.raises(ValueError, match="drive on joint 'joint2': max_force = 0 must be > 0"):
        sim.set_drive("joint2", fd.Drive(stiffness=1.0, max_force=0.0))


def test_bad_options(arm):
    with pytest.raises(ValueError, match="solver = 'xyz': must be 'pgs' or 'tgs'"):
        fd.Simulation(arm, solver="xyz")
    with pytest.raises(ValueError, match="dt = 0 must be finite and > 0"):
        fd.Simulation(arm, dt=0.0)
    with pytest.raises(ValueError, match=r"position_iterations = 0 is out of range \[1, "):
        fd.Batch(arm, 2, position_iterations=0)
    with pytest.raises(ValueError, match="drive type = 'spring'"):
        fd.Simulation(arm).set_drive_gains(1.0, 1.0, "spring")
    with pytest.raises(ValueError, match=r"step: count = -1 is out of range \[0, 2147483647\]"):
        fd.Simulation(arm).step(-1)


def test_batch_errors(arm):
    batch = fd.Batch(arm, 4)
    with pytest.raises(ValueError, match=r"positions has shape \(3, 7\), expected \(4, 7\) or \(7,\)"):
        batch.set_drive_targets(np.zeros((3, 7)))
    with pytest.raises(ValueError, match=r"q has shape \(4, 6\)"):
        batch.set_q(np.zeros((4, 6)))
    with pytest.raises(ValueError, match="stiffness has dtype complex128"):
        batch.set_drive_gains(np.zeros((4, 7), dtype=complex), np.zeros((4, 7)))
    kp = np.full((4, 7), 10.0)
    kp[2, 1] = -1.0
    with pytest.raises(ValueError, match="environment 2: set_drive_gains: dof 1: drive on joint 'joint2': stiffness = -1"):
        batch.set_drive_gains(kp, np.zeros((4, 7)))
    assert all(batch.sim(i).drive(1).type == fd.DriveType.none for i in range(4))
    with pytest.raises(ValueError, match=r"environment 1: qd\[3\] = nan is not finite"):
        qd = np.zeros((4, 7))
        qd[1, 3] = np.nan
        batch.set_qd(qd)
    with pytest.raises(ValueError, match="no joint named 'hip'"):
        batch.set_drive("hip", fd.Drive())
    with pytest.raises(ValueError, match=r"environment index 4 is out of range \[0, 4\)"):
        batch.sim(4)
    with pytest.raises(ValueError, match=r"num_threads = -1 is out of range \[0, "):
        batch.num_threads = -1
    with pytest.raises(ValueError, match=r"count = 0 is out of range \[1, "):
        fd.Batch(arm, 0)


def test_model_and_file_errors(tmp_path):
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("base", "", 0.0, [0, 0, 0], np.zeros((3, 3)), fd.fixed_joint("world")))
    b.add_link(fd.make_link("arm", "base", -1.0, [0, 0, 0], np.eye(3), fd.revolute_joint("j", [0, 0, 1])))
    with pytest.raises(fd.ModelError, match="arm") as err:
        b.build()
    assert isinstance(err.value, ValueError)
    with pytest.raises(ValueError, match=r"axis has shape \(2,\), expected \(3,\)"):
        fd.revolute_joint("j", [0, 1])
    with pytest.raises(ValueError, match=r"inertia has shape \(3,\), expected \(3, 3\)"):
        fd.make_link("l", "", 1.0, [0, 0, 0], [1, 1, 1], fd.fixed_joint("w"))
    missing = tmp_path / "missing.urdf"
    with pytest.raises(ValueError, match="missing.urdf"):
        fd.load_urdf(str(missing))
    bad = tmp_path / "bad.yaml"
    bad.write_text("model: nowhere.urdf\nsteps: 10\nsolver: {type: xgs}\n")
    with pytest.raises(ValueError, match="bad.yaml"):
        fd.load_scene(str(bad))


def test_deep_and_long_urdfs():
    # 100 000 nested elements: refused before the XML reader recurses (it would overflow the stack).
    deep = '<robot name="r">' + "<a>" * 100000 + "</a>" * 100000 + "</robot>"
    with pytest.raises(ValueError, match="deep.urdf: line 1: elements nested deeper than 100"):
        fd.parse_urdf(deep, "deep.urdf")
    # A link that is the child of two joints, before a cycle through it could loop.
    two = ('<robot name="r"><link name="a"/><link name="b"/><link name="c"/>'
           '<joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>'
           '<joint name="j2" type="fixed"><parent link="b"/><child link="c"/></joint>'
           '<joint name="j3" type="fixed"><parent link="c"/><child link="b"/></joint></robot>')
    with pytest.raises(ValueError, match="link 'b' is the child of two joints, 'j1' and 'j3'"):
        fd.parse_urdf(two, "two.urdf")
    # A 5 000-link chain imports, every joint a dof.
    links = "".join(f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="1" iyy="1" '
                    f'izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>' for i in range(5001))
    joints = "".join(f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/>'
                     f'<child link="l{i}"/><axis xyz="0 0 1"/>'
                     f'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
                     for i in range(1, 5001))
    robot = fd.parse_urdf(f'<robot name="chain">{links}{joints}</robot>', "chain.urdf")
    assert robot.model.nv == 5000


# ---- integers: 64-bit range checks before narrowing; numpy integers are integers --------------

class Index:
    """Not an int, but usable as one (__index__), as numpy integers are."""

    def __init__(self, value):
        self.value = value

    def __index__(self):
        return self.value


INT_MAX = 2**31 - 1


def out_of_range(what, value, lo, hi):
    return rf"{what} = {value} is out of range \[{lo}, {hi}\]"


@pytest.fixture
def scene():
    import conftest
    return fd.load_scene(str(conftest.ROOT / "examples" / "arm7_tgs.yaml"))


@pytest.mark.parametrize("value", [2**31, 2**32 + 1, 2**40, 2**63, 2**64 + 5, -1, -2**63 - 1])
def test_step_counts_out_of_range(arm, value):
    sim, batch = fd.Simulation(arm), fd.Batch(arm, 2)
    with pytest.raises(ValueError, match=out_of_range("step: count", value, 0, INT_MAX)):
        sim.step(value)
    with pytest.raises(ValueError, match=out_of_range("step: count", value, 0, INT_MAX)):
        batch.step(value)
    assert sim.step_count == 0 and batch.sim(1).step_count == 0


@pytest.mark.parametrize("count", [np.int64(3), np.int32(3), np.uint8(3), np.int16(3), Index(3), 3])
def test_integer_like_counts_are_integers(arm, count):
    sim, batch = fd.Simulation(arm), fd.Batch(arm, 2)
    sim.step(count)
    batch.step(count)
    assert sim.step_count == 3 and batch.sim(0).step_count == 3


@pytest.mark.parametrize("bad", [1.0, np.float64(2.0), True, np.bool_(True), "3", None, [1]])
def test_non_integers_are_type_errors(arm, bad):
    sim, batch = fd.Simulation(arm), fd.Batch(arm, 2)
    calls = [lambda: sim.step(bad), lambda: batch.step(bad), lambda: batch.sim(bad),
             lambda: fd.Batch(arm, bad), lambda: fd.Batch(sim, bad),
             lambda: setattr(batch, "num_threads", bad), lambda: batch.set_num_threads(bad),
             lambda: fd.Simulation(arm, position_iterations=bad),
             lambda: fd.SimulationOptions(velocity_iterations=bad)]
    for call in calls:
        with pytest.raises(TypeError, match="must be an integer|expected") as err:
            call()
        assert "Unable to cast" not in str(err.value)
    assert sim.step_count == 0


@pytest.mark.parametrize("field, value, lo", [
    ("position_iterations", 4294967297, 1), ("velocity_iterations", 4294967296, 0),
    ("position_iterations", 2**31, 1), ("velocity_iterations", -1, 0),
    ("position_iterations", 0, 1), ("velocity_iterations", 2**70, 0)])
def test_iteration_counts_out_of_range(arm, field, value, lo):
    message = out_of_range(field, value, lo, INT_MAX)
    with pytest.raises(ValueError, match=message):
        fd.Simulation(arm, **{field: value})
    with pytest.raises(ValueError, match=message):
        fd.Batch(arm, 2, **{field: value})
    with pytest.raises(ValueError, match=message):
        fd.SimulationOptions(**{field: value})
    options = fd.SimulationOptions()
    with pytest.raises(ValueError, match=message):
        setattr(options, field, value)
    assert (options.position_iterations, options.velocity_iterations) == (4, 1)
    setattr(options, field, np.int64(7))
    assert getattr(options, field) == 7


def test_batch_sizes_indices_and_threads(arm):
    most = 2**24  # Batch::kMaxSize
    with pytest.raises(ValueError, match=out_of_range("count", 2**31, 1, most)):
        fd.Batch(arm, 2**31)
    with pytest.raises(ValueError, match=out_of_range("count", 2**32 + 2, 1, most)):
        fd.Batch(fd.Simulation(arm), 2**32 + 2)
    with pytest.raises(ValueError, match=out_of_range("count", most + 1, 1, most)):
        fd.Batch(arm, most + 1)
    with pytest.raises(ValueError, match=out_of_range("count", -3, 1, most)):
        fd.Batch(arm, -3)
    batch = fd.Batch(arm, np.int64(4))
    assert len(batch) == 4 and len(fd.Batch(fd.Simulation(arm), Index(2))) == 2
    for i in [4, 2**32, 2**32 + 1, -1, -2**32]:
        with pytest.raises(ValueError, match=rf"environment index {i} is out of range \[0, 4\)"):
            batch.sim(i)
    with pytest.raises(ValueError,
                       match=out_of_range("environment index", 2**64, -2**63, 2**63 - 1)):
        batch.sim(2**64)
    assert batch.sim(np.int64(3)).step_count == 0 and batch.sim(Index(1)) is not None
    for t in [2**31, 2**32, -1]:
        with pytest.raises(ValueError, match=out_of_range("num_threads", t, 0, INT_MAX)):
            batch.num_threads = t
        with pytest.raises(ValueError, match=out_of_range("num_threads", t, 0, INT_MAX)):
            batch.set_num_threads(t)
    for t in [4097, INT_MAX]:  # a huge TBB arena crashed
        with pytest.raises(ValueError, match=rf"num_threads = {t} must be in \[0, 4096\]"):
            batch.num_threads = t
    batch.num_threads = np.int8(2)
    assert batch.num_threads == 2
    batch.set_num_threads(4096)
    batch.step(1)
    assert batch.effective_num_threads() == 4096 and batch.sim(0).step_count == 1


@pytest.mark.parametrize("joint", [np.int64(2), np.int32(2), np.uint16(2), Index(2), 2])
def test_dof_indices_take_numpy_integers(arm, joint):
    sim = fd.Simulation(arm)
    sim.set_drive(joint, fd.Drive(stiffness=7.0))
    sim.set_drive_target(joint, 0.25)
    sim.set_joint_limits(joint, -1.0, 1.0)
    sim.set_max_joint_velocity(joint, 3.0)
    sim.set_friction_coefficient(joint, 0.1)
    sim.set_joint_friction(joint, fd.JointFriction(0.2))
    sim.set_actuator_envelope(joint, fd.ActuatorEnvelope(5.0))
    assert sim.drive(joint).stiffness == 7.0 == sim.drive("joint3").stiffness
    assert sim.drive(joint).target_position == 0.25 and sim.upper_limit(joint) == 1.0
    assert sim.lower_limit(joint) == -1.0 and sim.max_joint_velocity(joint) == 3.0
    assert sim.friction_coefficient(joint) == 0.1
    assert sim.joint_friction(joint).static_effort == 0.2
    assert sim.actuator_envelope(joint).max_effort == 5.0
    sim.set_link_parameters(joint, fd.LinkParameters(0.5))
    assert sim.link_parameters(joint).cfm_scale == 0.5


@pytest.mark.parametrize("index", [7, 2**32, 2**32 + 2, 2**40, -1, -2**32 + 1, 2**63 - 1])
def test_dof_and_link_indices_out_of_range(arm, index):
    sim = fd.Simulation(arm)
    dof = rf"dof index {index} is out of range \[0, 7\)"
    for call in [lambda: sim.drive(index), lambda: sim.set_drive(index, fd.Drive()),
                 lambda: sim.set_drive_target(np.int64(index), 0.0),
                 lambda: sim.set_joint_limits(index, -1, 1), lambda: sim.upper_limit(index),
                 lambda: sim.set_joint_friction(index, fd.JointFriction()),
                 lambda: sim.set_max_joint_velocity(index, 1.0),
                 lambda: sim.friction_coefficient(index),
                 lambda: sim.actuator_envelope(index)]:
        with pytest.raises(ValueError, match=dof):
            call()
    links = arm.num_links()
    if not 0 <= index < links:
        link = rf"link index {index} is out of range \[0, {links}\)"
        with pytest.raises(ValueError, match=link):
            sim.link_parameters(index)
        with pytest.raises(ValueError, match=link):
            sim.set_link_parameters(index, fd.LinkParameters())
    # Nothing was narrowed onto a valid index: dof 0 and link 0 are as they were.
    assert sim.drive(0).type == fd.DriveType.none and sim.link_parameters(0).cfm_scale == 0.0


def test_apply_targets_step_index(arm, scene):
    sim = fd.make_simulation(scene)
    for k in [INT_MAX, 2**31, 2**40, -1]:
        with pytest.raises(ValueError,
                           match=out_of_range("apply_targets: step_index", k, 0, INT_MAX - 1)):
            fd.apply_targets(scene, sim, k)
    fd.apply_targets(scene, sim, INT_MAX - 1)  # (k + 1) dt with k + 1 = 2**31 - 1: no overflow
    t = INT_MAX * scene.options.dt
    for spec in scene.drives:
        if spec.sine is not None:
            assert sim.drive(spec.dof).target_position == spec.sine.position(t)
    fd.apply_targets(scene, sim, np.int64(4))
    t = 5 * scene.options.dt
    sines = [s for s in scene.drives if s.sine is not None]
    assert sines and all(sim.drive(s.dof).target_position == s.sine.position(t) for s in sines)
    with pytest.raises(TypeError, match="apply_targets: step_index must be an integer, not float"):
        fd.apply_targets(scene, sim, 4.0)


# ---- exceptions: TypeError for wrong types, never RuntimeError("Unable to cast") -------------

@pytest.mark.parametrize("bad", [1.5, None, [0], {"a": 1}, np.float32(1), b"joint1"])
def test_wrong_types_for_joints_and_links(arm, bad):
    sim = fd.Simulation(arm)
    calls = {
        "link_parameters": lambda: sim.link_parameters(bad),
        "set_link_parameters": lambda: sim.set_link_parameters(bad, fd.LinkParameters()),
        "drive": lambda: sim.drive(bad),
        "set_drive": lambda: sim.set_drive(bad, fd.Drive()),
        "set_drive_target": lambda: sim.set_drive_target(bad, 0.0),
        "set_joint_limits": lambda: sim.set_joint_limits(bad, -1, 1),
        "lower_limit": lambda: sim.lower_limit(bad),
        "joint_friction": lambda: sim.joint_friction(bad),
        "set_max_joint_velocity": lambda: sim.set_max_joint_velocity(bad, 1.0),
        "friction_coefficient": lambda: sim.friction_coefficient(bad),
        "set_actuator_envelope": lambda: sim.set_actuator_envelope(bad, fd.ActuatorEnvelope()),
        "batch.set_drive": lambda: fd.Batch(arm, 2).set_drive(bad, fd.Drive()),
    }
    for name, call in calls.items():
        with pytest.raises(TypeError) as err:
            call()
        message = str(err.value)
        assert "Unable to cast" not in message, name
        assert ("link" if "link" in name else "joint") in message, (name, message)


def test_link_parameters_of_a_float_names_the_argument(arm):
    with pytest.raises(TypeError, match=r"link = 1.5: expected a link name \(str\) or a link "
                                        r"index \(int\), not float"):
        fd.Simulation(arm).link_parameters(1.5)
    with pytest.raises(TypeError, match=r"joint = 1.5: expected a joint name \(str\) or a dof "
                                        r"index \(int\), not float"):
        fd.Simulation(arm).drive(1.5)


@pytest.mark.parametrize("call, message", [
    (lambda arm: fd.Simulation(arm, solver=3),
     "solver = 3: expected 'pgs' or 'tgs' or a SolverType, not int"),
    (lambda arm: fd.Simulation(arm, compat=1.0),
     "compat = 1.0: expected 'none' or 'physx' or a Compat"),
    (lambda arm: fd.Drive(type=2), "drive type = 2: expected 'none', 'force' or 'acceleration'"),
    (lambda arm: fd.Simulation(arm).set_drive_gains(1.0, 1.0, None), "drive type = None"),
    (lambda arm: fd.Batch(arm, 2, solver=b"pgs"), "solver = b'pgs'"),
])
def test_wrong_enum_types(arm, call, message):
    with pytest.raises(TypeError, match=message):
        call(arm)


def test_bad_strings_are_value_errors(arm):
    """A str that is no valid name (or not even UTF-8 encodable) is a bad value."""
    sim = fd.Simulation(arm)
    for bad in ["\udcff", "joint1\x00"]:
        with pytest.raises(ValueError):
            sim.drive(bad)
        with pytest.raises(ValueError):
            fd.Simulation(arm, solver=bad)
        with pytest.raises(ValueError):
            sim.link_parameters(bad)


def test_dynamics_numbers_must_be_finite(arm):
    """A NaN point or acceleration is refused naming the entry, not answered with NaN."""
    q = np.zeros(arm.nv)
    with pytest.raises(ValueError, match=r"point\[1\] = nan: must be finite"):
        fd.frame_position(arm, q, 3, [0.0, float("nan"), 0.0])
    with pytest.raises(ValueError, match=r"qdd\[6\] = inf: must be finite"):
        fd.inverse_dynamics(arm, q, q, np.r_[np.zeros(6), np.inf])
    sim = fd.Simulation(arm)
    with pytest.raises(ValueError, match=r"point\[0\] = -inf"):
        sim.frame_position(3, [-np.inf, 0.0, 0.0])


def test_drive_targets_beyond_the_representable_range(arm):
    """docs/math/implicit_drives.md eq. T3: |x_T| <= 1e6 on a drive with stiffness."""
    sim = fd.Simulation(arm, stiffness=100.0, damping=10.0)
    sim.set_drive_target("joint2", 1e6, 0.0)
    with pytest.raises(ValueError, match=r"joint 'joint2'.*target_position = 1e\+20 is beyond"):
        sim.set_drive_target("joint2", 1e20, 0.0)
    assert sim.drive("joint2").target_position == 1e6
    batch = fd.Batch(sim, 2)
    with pytest.raises(ValueError, match="target_velocity = 2e\\+10 is beyond"):
        batch.set_drive_targets(np.zeros(7), np.full(7, 2e10))
