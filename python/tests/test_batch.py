"""A Batch of N copies equals N separate simulations bit for bit, whatever the thread count; a
divergence names the copy."""
import re

import numpy as np
import pytest

import featherdrive as fd
from conftest import in_lanes

N = 64
STEPS = 30


def targets(n, nv):
    """Different targets for every copy."""
    i = np.arange(n)[:, None]
    d = np.arange(nv)[None, :]
    return 0.6 * np.sin(0.37 * i + 1.1 * d), 0.2 * np.cos(0.23 * i - 0.5 * d)


def gains(n, nv):
    i = np.arange(n)[:, None]
    d = np.arange(nv)[None, :]
    return 200.0 + 150.0 * i + 10.0 * d, 5.0 + 0.5 * i + 1.0 * d


def separate(model, solver, pos, vel, kp, kd):
    """Each copy simulated on its own, one Simulation at a time."""
    q, qd, f = [], [], []
    for i in range(pos.shape[0]):
        sim = fd.Simulation(model, dt=1.0 / 60.0, solver=solver, position_iterations=4,
                            velocity_iterations=1)
        sim.set_q(model.neutral_configuration() + 0.01 * i)
        sim.set_drive_gains(kp[i], kd[i])
        sim.set_drive_targets(pos[i], vel[i])
        sim.step(STEPS)
        q.append(np.array(sim.q))
        qd.append(np.array(sim.qd))
        f.append(np.array(sim.drive_force))
    return np.array(q), np.array(qd), np.array(f)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
@pytest.mark.parametrize("lanes", [False, True])
def test_batch_equals_separate_simulations_for_any_thread_count(arm, solver, lanes):
    """Without lanes each copy is its Simulation bit for bit; in SIMD lanes (arm7 as loaded,
    velocity limits included) within 1e-12, and the same bits for any thread count."""
    pos, vel = targets(N, arm.nv)
    kp, kd = gains(N, arm.nv)
    expected = separate(arm, solver, pos, vel, kp, kd)
    first = None
    for threads in (1, 0, 3):
        batch = fd.Batch(arm, N, dt=1.0 / 60.0, solver=solver, position_iterations=4,
                         velocity_iterations=1)
        batch.num_threads = threads
        batch.lanes = lanes
        assert in_lanes(batch.step_path) == lanes, batch.step_path
        assert batch.effective_num_threads() >= 1
        batch.set_q(arm.neutral_configuration()[None, :] + 0.01 * np.arange(N)[:, None])
        batch.set_drive_gains(kp, kd)
        batch.set_drive_targets(pos, vel)
        batch.step(STEPS)
        assert batch.q.shape == (N, arm.nq) and batch.qd.shape == (N, arm.nv)
        assert batch.drive_force.shape == (N, arm.nv) and batch.limit_force.shape == (N, arm.nv)
        for got, want in zip((batch.q, batch.qd, batch.drive_force), expected):
            if lanes:
                assert np.max(np.abs(got - want)) <= 1e-12 * max(1.0, np.max(np.abs(want)))
            else:
                np.testing.assert_array_equal(bits(got), bits(want), err_msg=f"threads={threads}")
        if first is None:
            first = bits(batch.qd).copy()
        np.testing.assert_array_equal(bits(batch.qd), first, err_msg=f"threads={threads}")
        assert all(batch.sim(i).step_count == STEPS for i in range(N))
    # The copies really differ.
    assert len({row.tobytes() for row in expected[0]}) == N


def test_batch_from_prototype_and_per_copy_access(arm, monkeypatch):
    monkeypatch.setenv("FEATHERDRIVE_SIMD", "scalar")  # each copy bit for bit as its Simulation
    proto = fd.Simulation(arm, solver="tgs")
    proto.set_drive_gains(800.0, 30.0)
    proto.set_drive_targets(np.full(arm.nv, 0.4), np.zeros(arm.nv))
    batch = fd.Batch(proto, 4)
    assert len(batch) == 4 and batch.size() == 4
    batch.sim(2).set_drive_target("joint2", -0.3, 0.0)
    batch.step(10)
    alone = proto.copy()
    alone.set_drive_target("joint2", -0.3, 0.0)
    alone.step(10)
    proto.step(10)
    np.testing.assert_array_equal(batch.q[2], alone.q)
    np.testing.assert_array_equal(batch.q[0], proto.q)
    assert not np.array_equal(batch.q[0], batch.q[2])
    assert not batch.q.flags.writeable
    # sim(i) views into the batch: they see the batch's later steps.
    view = batch.sim(1).q
    batch.step()
    np.testing.assert_array_equal(view, batch.q[1])


def test_divergence_names_the_copy_and_leaves_the_others_stepping(arm):
    batch = fd.Batch(arm, 8, dt=0.01)
    batch.num_threads = 0
    # An applied force of 1e308 overflows the velocity at the first step of copy 5 (a target of
    # 1e300 is refused now: docs/math/implicit_drives.md eq. T3).
    force = np.zeros(7)
    force[3] = 1e308
    batch.sim(5).set_applied_force(force)
    q0 = np.array(batch.q)
    with pytest.raises(fd.DivergenceError, match=r"batch copy 5 \(1 of 8 copies diverged\)") as err:
        batch.step(5)
    assert isinstance(err.value, RuntimeError)
    assert "simulation diverged at step 1" in str(err.value)
    # The diverged copy keeps the state from before the step that diverged ...
    assert batch.sim(5).step_count == 0
    np.testing.assert_array_equal(batch.q[5], q0[5])
    # ... and every other copy made all its steps, as it would have alone.
    alone = fd.Simulation(arm, dt=0.01)
    alone.step(5)
    for i in (0, 1, 2, 3, 4, 6, 7):
        assert batch.sim(i).step_count == 5
        np.testing.assert_array_equal(batch.q[i], alone.q)


def slider():
    """A 2.5 kg cube sliding along z without limits."""
    b = fd.ModelBuilder()
    b.add_link(fd.make_link("base", "", 0.0, [0, 0, 0], np.zeros((3, 3)), fd.fixed_joint("world")))
    b.add_link(fd.make_link("carriage", "base", 2.5, [0, 0, 0], 0.004 * np.eye(3),
                            fd.prismatic_joint("slide", [0, 0, 1])))
    return b.build()


def test_divergence_in_the_middle_of_a_long_step(arm):
    """On the main thread step(n) runs in chunks (between them it checks for Ctrl-C): copies that
    diverge mid-run (a huge applied force overflows after some hundred steps) stop where they would
    alone, the others make all n steps, and the error is that of one uninterrupted call (made
    from another thread, which steps in one go)."""
    import threading
    model, forces = slider(), [0.0, 1e153, 3.0, 1e154, -2.0]
    lone = []
    for f in forces:
        sim = fd.Simulation(model, dt=0.01)
        sim.set_applied_force([f])
        try:
            sim.step(1000)
            lone.append((sim, None))
        except fd.DivergenceError as e:
            lone.append((sim, str(e)))
    assert [s.step_count for s, _ in lone] == [1000, 651, 1000, 206, 1000]
    results = []
    for on_main in (True, False):
        batch = fd.Batch(model, len(forces), dt=0.01)
        batch.set_applied_force(np.array(forces)[:, None])
        errors = []

        def step():
            try:
                batch.step(1000)
            except fd.DivergenceError as e:
                errors.append(str(e))

        if on_main:
            step()
        else:
            thread = threading.Thread(target=step)
            thread.start()
            thread.join()
        assert errors == ["batch copy 1 (2 of 5 copies diverged): " + lone[1][1]]
        for i, (sim, _) in enumerate(lone):
            assert batch.sim(i).step_count == sim.step_count
            np.testing.assert_array_equal(bits(batch.q[i]), bits(sim.q))
        results.append(errors[0])
    assert results[0] == results[1]


def test_simulation_divergence_is_runtime_error(arm):
    sim = fd.Simulation(arm, dt=0.01)
    sim.step(2)
    q = np.array(sim.q)
    force = np.zeros(7)
    force[1] = 1e308
    sim.set_applied_force(force)
    with pytest.raises(RuntimeError, match="diverged at step 3"):
        sim.step()
    assert sim.step_count == 2
    np.testing.assert_array_equal(sim.q, q)


def test_batch_compat_physx_is_each_copy_s_compat_physx_simulation(arm):
    batch = fd.Batch(arm, 3, compat="physx")
    alone = fd.Simulation(arm, compat="physx")
    assert batch.sim(1).options.compat == fd.Compat.physx
    assert batch.sim(1).friction_coefficient(0) == alone.friction_coefficient(0) == 0.05
    q0 = arm.neutral_configuration() + 0.3
    batch.set_q(np.tile(q0, (3, 1)))
    alone.set_q(q0)
    # A fixed base of revolute joints: compat physx steps in the lanes, within 1e-12 of the
    # Simulation (another operation order); with lanes off, bit for bit.
    assert in_lanes(batch.step_path), batch.step_path
    scalar = fd.Batch(batch.sim(0), 3)
    scalar.lanes = False
    scalar.set_q(np.tile(q0, (3, 1)))
    batch.step(20)
    scalar.step(20)
    alone.step(20)
    np.testing.assert_allclose(batch.q[2], alone.q, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(bits(scalar.q[2]), bits(alone.q))


def test_batch_with_gravity_per_environment_steps_in_lanes(arm):
    """Gravity is each lane's own (docs/simd_batch.md, "Lane groups"): a batch of randomised
    gravity stays one lane group, within 1e-12 of the same batch stepped as Simulations."""
    n = 6
    g = np.zeros((n, 3))
    g[:, 2] = -9.81 + np.arange(n)
    g[:, 0] = 0.3 * np.arange(n)
    batch = fd.Batch(arm, n)
    batch.set_gravity(g)
    batch.set_gravity([0.0, 0.0, -1.0], env_ids=[5])
    g[5] = [0.0, 0.0, -1.0]
    np.testing.assert_array_equal(batch.gravity(), g)
    assert in_lanes(batch.step_path), batch.step_path
    assert re.search(r" lanes, group 0( \(one lane\))?$", batch.env_path(3)), batch.env_path(3)
    scalar = fd.Batch(batch.sim(0), n)
    scalar.set_gravity(g)
    scalar.lanes = False
    assert scalar.env_path(3) == "scalar: lanes off (set_lanes)"
    batch.step(50)
    scalar.step(50)
    np.testing.assert_allclose(batch.q, scalar.q, rtol=1e-12, atol=1e-12)
    assert np.abs(batch.q[0] - batch.q[4]).max() > 1e-3  # the gravity acted
    with pytest.raises(ValueError, match="gravity"):
        batch.set_gravity([0.0, np.nan, 0.0], env_ids=[1])
    with pytest.raises(ValueError):
        batch.env_path(n)
