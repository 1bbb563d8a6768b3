"""Views stay valid for their object's life: every view of a Simulation (and of a copy inside a
Batch) taken once shows, after any state-changing call, exactly the values of a twin that went
through the same calls (no operation reallocates or swaps the memory under a view). Settings read
back (options, drive(), Scene.robot, ...) are copies. Run these also under PYTHONMALLOC=malloc
(and valgrind) to catch a read of freed memory."""
import gc

import numpy as np
import pytest

import featherdrive as fd
import conftest
from conftest import hexes

VIEWS = ["q", "qd", "applied_force", "drive_force", "limit_force", "friction_force",
         "velocity_limit_force"]


def driven(model, solver="tgs"):
    """Drives, limits that act, friction and a velocity limit: every output is nonzero."""
    sim = conftest.driven(model, solver)
    for d in range(model.nv):
        sim.set_joint_limits(d, -0.2, 0.25)  # limit forces act
        sim.set_joint_friction(d, fd.JointFriction(0.5, 0.4, 0.1))
    sim.set_max_joint_velocity(0, 0.05)
    return sim


def address(view):
    return view.__array_interface__["data"][0]


def fresh(sim):
    """A snapshot of every vector, read through new views."""
    return {name: np.array(getattr(sim, name)) for name in VIEWS}


def check(views, sim, expected):
    for name in VIEWS:
        assert address(views[name]) == address(getattr(sim, name)), name  # same memory
        assert hexes(views[name]) == hexes(expected[name]), name


def save(tmp_path, sim, name):
    path = tmp_path / name
    fd.save_checkpoint(sim, path)
    return path


def diverge(sim):
    """A step that raises DivergenceError and restores the state from before it."""
    force = np.array(sim.applied_force)
    huge = force.copy()
    huge[3] = 1e308  # the velocity overflows to inf
    sim.set_applied_force(huge)
    with pytest.raises(fd.DivergenceError):
        sim.step(3)
    sim.set_applied_force(force)


def truncated_checkpoint(sim, tmp_path):
    path = save(tmp_path, sim, "cut.bin")
    path.write_bytes(path.read_bytes()[:40])
    with pytest.raises(fd.CheckpointError):
        fd.load_checkpoint(path, sim)


# Calls that change a simulation's state or settings, each run on the simulation and its twin.
OPERATIONS = {
    "step": lambda s, tmp: s.step(7),
    "step_0": lambda s, tmp: s.step(0),
    "set_q": lambda s, tmp: s.set_q(np.linspace(0.1, 0.7, s.model.nq)),
    "set_qd": lambda s, tmp: s.set_qd(np.linspace(-1, 1, s.model.nv)),
    "set_applied_force": lambda s, tmp: s.set_applied_force(np.full(s.model.nv, 3.0)),
    "set_options": lambda s, tmp: s.set_options(fd.SimulationOptions(0.002, "pgs", 9, 3)),
    "set_drive_gains": lambda s, tmp: s.set_drive_gains(50.0, 2.0),
    "set_drive_targets": lambda s, tmp: fd.set_drive_targets(s, np.ones(s.model.nv),
                                                             np.zeros(s.model.nv)),
    "set_joint_limits": lambda s, tmp: s.set_joint_limits("joint3", -1.0, 1.0),
    "set_link_parameters": lambda s, tmp: s.set_link_parameters(2, fd.LinkParameters(0.1, 0.5)),
    "copy_and_step_copy": lambda s, tmp: s.copy().step(5),
    "batch_of_it": lambda s, tmp: fd.Batch(s, 3).step(2),
    "divergence": lambda s, tmp: diverge(s),
    "truncated_checkpoint": truncated_checkpoint,
}


@pytest.mark.parametrize("operation", sorted(OPERATIONS))
def test_views_follow_every_operation(arm, tmp_path, operation):
    sim, twin = driven(arm), driven(arm)
    sim.step(4)
    twin.step(4)
    views = {name: getattr(sim, name) for name in VIEWS}
    for k in range(3):  # each operation three times, with steps between
        OPERATIONS[operation](sim, tmp_path)
        OPERATIONS[operation](twin, tmp_path)
        sim.step(2)
        twin.step(2)
        check(views, sim, fresh(twin))
    assert sim.step_count == twin.step_count


def test_views_show_a_loaded_checkpoint(arm, tmp_path):
    """load_checkpoint restores in place: the old views show the saved state, bit for bit, also
    after the garbage of other simulations was collected over the old memory."""
    sim = driven(arm)
    views = {name: getattr(sim, name) for name in VIEWS}
    for k, (steps, solver) in enumerate([(5, "tgs"), (0, "pgs"), (13, "pgs"), (2, "tgs")]):
        other = driven(arm, solver)
        other.set_applied_force(np.full(arm.nv, 0.5 * k))
        other.step(steps)
        expected = fresh(other)
        path = save(tmp_path, other, f"state{k}.bin")
        del other
        gc.collect()
        sim.step(3)
        fd.load_checkpoint(path, sim)
        garbage = [driven(arm) for _ in range(4)]  # reuse whatever memory was freed
        check(views, sim, expected)
        assert sim.step_count == steps
        del garbage
    sim.step(1)
    check(views, sim, fresh(sim))


def test_views_of_a_batch_copy_follow_batch_operations(arm, tmp_path):
    batch = fd.Batch(driven(arm), 4)
    batch.lanes = False  # without SIMD lanes a batch copy is bit-identical to stepping it alone
    twin = driven(arm)
    copy = batch.sim(2)
    views = {name: getattr(copy, name) for name in VIEWS}
    del copy
    gc.collect()
    q = np.tile(np.linspace(-0.3, 0.3, arm.nq), (4, 1))
    steps = [
        (lambda b: b.step(6), lambda s: s.step(6)),
        (lambda b: b.set_q(q), lambda s: s.set_q(q[2])),
        (lambda b: b.set_qd(np.full(arm.nv, 0.4)), lambda s: s.set_qd(np.full(arm.nv, 0.4))),
        (lambda b: b.set_options(fd.SimulationOptions(0.005, "pgs", 6, 2)),
         lambda s: s.set_options(fd.SimulationOptions(0.005, "pgs", 6, 2))),
        (lambda b: b.set_drive_gains(np.full(arm.nv, 90.0), np.full(arm.nv, 3.0)),
         lambda s: s.set_drive_gains(90.0, 3.0)),
        (lambda b: b.set_applied_force(np.full(arm.nv, -1.0)),
         lambda s: s.set_applied_force(np.full(arm.nv, -1.0))),
        (lambda b: b.set_num_threads(3), lambda s: None),
        (lambda b: b.step(9), lambda s: s.step(9)),
    ]
    for on_batch, on_twin in steps:
        on_batch(batch)
        on_twin(twin)
        check(views, batch.sim(2), fresh(twin))
    # A checkpoint loaded into the copy lands in the same memory.
    other = driven(arm)
    other.step(11)
    fd.load_checkpoint(save(tmp_path, other, "copy.bin"), batch.sim(2))
    check(views, batch.sim(2), fresh(other))
    assert hexes(batch.q[2]) == hexes(other.q)
    del batch
    gc.collect()
    assert hexes(views["q"]) == hexes(other.q)  # the view keeps the batch alive


def test_model_and_scene_views_outlive_their_owners():
    robot = fd.load_urdf(str(conftest.ARM))
    model = robot.model
    names = ["armature", "lower_limit", "upper_limit", "effort_limit", "velocity_limit",
             "damping", "friction", "gravity"]
    views = {name: getattr(model, name) for name in names}
    link_views = [(link.com, link.inertia_com, link.axis) for link in model.links]
    expected = {name: np.array(v) for name, v in views.items()}
    expected_links = [[np.array(v) for v in vs] for vs in link_views]
    robot.rebuild()  # gives the robot a new Model; the old one lives on through the views
    del robot, model
    gc.collect()
    again = fd.load_urdf(str(conftest.ARM)).model
    for name in names:
        assert hexes(views[name]) == hexes(expected[name]) == hexes(getattr(again, name))
    for vs, es in zip(link_views, expected_links):
        for v, e in zip(vs, es):
            assert hexes(v) == hexes(e)
    scene = fd.load_scene(str(conftest.ROOT / "examples" / "arm7_tgs.yaml"))
    q0, qd0 = scene.q0, scene.qd0
    q0_copy = np.array(q0)
    del scene
    gc.collect()
    assert hexes(q0) == hexes(q0_copy) and qd0.shape == (7,)


def test_settings_read_back_are_copies(arm):
    """Writing to what a getter returned never reaches the simulation past its checks."""
    sim = fd.Simulation(arm, dt=0.01)
    options = sim.options
    options.dt = 0.5
    options.position_iterations = 40
    assert sim.options.dt == 0.01 and sim.options.position_iterations == 4
    drive = sim.drive(0)
    drive.stiffness = -5.0  # would be refused by set_drive
    assert sim.drive(0).stiffness == 0.0
    scene = fd.load_scene(str(conftest.ROOT / "examples" / "arm7_tgs.yaml"))
    scene.options.dt = 123.0
    scene.robot.options.fixed_base = not scene.robot.options.fixed_base
    links = scene.robot.links
    scene.robot.links = links[:1]
    assert scene.options.dt != 123.0
    assert len(scene.robot.links) == len(links) == scene.model.num_links()


def test_init_again_changes_nothing(arm):
    """__init__ on a live object is ignored (pybind11): it frees nothing a view reads."""
    sim = driven(arm)
    sim.step(3)
    q = sim.q
    expected = np.array(q)
    sim.__init__(arm, dt=0.5)
    gc.collect()
    _ = [driven(arm) for _ in range(4)]
    assert hexes(q) == hexes(expected) and sim.step_count == 3 and sim.options.dt == 0.01
