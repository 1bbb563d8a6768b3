"""Simulations and Batches shared between Python threads: every call holds the object's lock, so
calls run one after another, each whole. Threads stepping one object make exactly the steps of
one thread, bit for bit; a thread loading checkpoints, setting inputs or copying while another
steps never crashes and only ever sees states a sequence of whole calls gives."""
import threading

import numpy as np
import pytest

import featherdrive as fd
from conftest import driven, hexes

THREADS = 4


def run_threads(*targets):
    """Runs the targets in threads started together; re-raises the first error of any."""
    barrier = threading.Barrier(len(targets))
    errors = []

    def wrap(target):
        def run():
            barrier.wait()
            try:
                target()
            except BaseException as e:  # noqa: B036 - reported to the test below
                errors.append(e)
        return run

    threads = [threading.Thread(target=wrap(t)) for t in targets]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if errors:
        raise errors[0]


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
@pytest.mark.parametrize("chunks", [[1] * 60, [1, 7, 3, 13, 2, 9, 25]])
def test_threads_stepping_one_simulation_make_every_step(arm, solver, chunks):
    sim, alone = driven(arm, solver), driven(arm, solver)
    run_threads(*[lambda: [sim.step(n) for n in chunks] for _ in range(THREADS)])
    alone.step(THREADS * sum(chunks))
    assert sim.step_count == alone.step_count == THREADS * sum(chunks)
    assert hexes(sim.q) == hexes(alone.q)
    assert hexes(sim.qd) == hexes(alone.qd)
    assert hexes(sim.drive_force) == hexes(alone.drive_force)


@pytest.mark.parametrize("num_threads", [1, 3])
def test_threads_stepping_one_batch_make_every_step(arm, num_threads):
    batch = fd.Batch(driven(arm), 6)
    batch.num_threads = num_threads
    batch.set_q(np.linspace(-0.4, 0.4, 6 * arm.nq).reshape(6, arm.nq))
    sequential = fd.Batch(driven(arm), 6)
    sequential.set_q(np.array(batch.q))
    run_threads(*[lambda: [batch.step(n) for n in (1, 4, 2, 8)] for _ in range(THREADS)])
    sequential.step(THREADS * 15)
    assert [batch.sim(i).step_count for i in range(6)] == [THREADS * 15] * 6
    assert hexes(batch.q) == hexes(sequential.q)
    assert hexes(batch.drive_force) == hexes(sequential.drive_force)


def test_a_batch_copy_and_its_batch_share_one_lock(arm):
    """Threads stepping the batch and threads stepping one copy of it: that copy makes all the
    steps of both, the others those of the batch."""
    batch = fd.Batch(driven(arm), 3)
    batch.num_threads = 2
    batch.lanes = False  # copy 1 steps alone too: bit for bit only as its own Simulation
    copy = batch.sim(1)
    run_threads(lambda: [batch.step(2) for _ in range(25)],
                lambda: [copy.step(1) for _ in range(40)],
                lambda: [batch.sim(1).step(3) for _ in range(10)])
    for i, steps in enumerate([50, 120, 50]):
        alone = driven(arm)
        alone.step(steps)
        assert batch.sim(i).step_count == steps
        assert hexes(batch.sim(i).q) == hexes(alone.q)


def trajectory(model, steps):
    """q after each number of steps 0..steps, as hex strings."""
    sim = driven(model)
    states = [hexes(sim.q)]
    for _ in range(steps):
        sim.step()
        states.append(hexes(sim.q))
    return states


def test_loading_checkpoints_while_another_thread_steps(arm, tmp_path):
    """A thread loads a checkpoint and snapshots (copy) in a loop while another steps: each
    snapshot is a state of the one trajectory at its own step_count."""
    steps = 300
    states = trajectory(arm, steps + 20)
    saved = driven(arm)
    saved.step(20)
    path = tmp_path / "at20.bin"
    fd.save_checkpoint(saved, path)
    sim = driven(arm)
    sim.step(20)
    seen = []

    def loader():
        for _ in range(60):
            fd.load_checkpoint(path, sim)
            snapshot = sim.copy()
            seen.append((snapshot.step_count, hexes(snapshot.q)))
            seen.append((sim.step_count, None))

    run_threads(lambda: [sim.step() for _ in range(steps)], loader)
    assert len(seen) == 120
    for count, q in seen:
        assert 20 <= count <= steps + 20
        if q is not None:
            assert q == states[count]
    final = sim.copy()
    assert hexes(final.q) == states[final.step_count]


def test_setters_copies_and_checkpoints_while_a_batch_steps(arm, tmp_path):
    """Calls that rewrite a batch's state, options and settings race a thread stepping it: no
    crash, and every copy ends finite at a whole number of steps with the inputs of some call."""
    batch = fd.Batch(driven(arm), 4)
    batch.num_threads = 2
    path = tmp_path / "copy.bin"
    fd.save_checkpoint(driven(arm), path)
    n = arm.nv

    def writer():
        for k in range(40):
            batch.set_q(np.full(arm.nq, 0.01 * k))
            batch.set_qd(np.zeros(n))
            batch.set_options(fd.SimulationOptions(0.01, ("pgs", "tgs")[k % 2], 4 + k % 3, 1))
            batch.set_drive_gains(np.full(n, 500.0 + k), np.full(n, 20.0))
            batch.set_drive_targets(np.full(n, 0.1 * (k % 5)))
            fd.load_checkpoint(path, batch.sim(k % 4))
            copy = batch.sim(k % 4).copy()
            copy.step(2)
            fd.Batch(batch.sim((k + 1) % 4), 2).step(1)
            assert np.all(np.isfinite(batch.q)) and batch.num_threads == 2

    def single_sim_writer():
        sim = batch.sim(3)
        for k in range(40):
            sim.set_q(np.full(arm.nq, -0.01 * k))
            sim.set_drive(k % n, fd.Drive(stiffness=100.0 + k, damping=5.0))
            sim.set_options(fd.SimulationOptions(0.01, "tgs", 2, 0))
            sim.step(2)

    run_threads(lambda: [batch.step(3) for _ in range(60)], writer, single_sim_writer)
    assert np.all(np.isfinite(batch.q)) and np.all(np.isfinite(batch.drive_force))
    batch.step(2)
    assert np.all(np.isfinite(batch.q))


def test_standalone_simulation_checkpoint_and_copy_race(arm, tmp_path):
    """save_checkpoint, load_checkpoint, set_q, copy and Batch(sim) on one simulation from three
    threads while a fourth steps it: no crash; what was saved loads again."""
    sim = driven(arm)
    paths = [tmp_path / f"s{i}.bin" for i in range(2)]
    fd.save_checkpoint(sim, paths[0])

    def saver():
        for k in range(40):
            fd.save_checkpoint(sim, paths[1])
            fd.load_checkpoint(paths[k % 2], sim)

    def setter():
        for k in range(40):
            sim.set_q(np.full(arm.nq, 0.02 * (k % 7)))
            sim.set_applied_force(np.full(arm.nv, 0.1 * k))
            sim.set_joint_limits(k % arm.nv, -1.0, 1.0)

    def copier():
        for _ in range(40):
            assert np.all(np.isfinite(sim.copy().q))
            fd.Batch(sim, 2).step(1)

    run_threads(lambda: [sim.step(2) for _ in range(80)], saver, setter, copier)
    check = driven(arm)
    fd.load_checkpoint(paths[1], check)
    assert np.all(np.isfinite(check.q)) and check.step_count >= 0


def test_views_read_from_another_thread_do_not_crash(arm):
    """Views are not synchronised (a read during a step may see a half-written vector), but
    reading them while another thread steps is memory-safe."""
    sim = driven(arm)
    q, f = sim.q, sim.drive_force
    done = threading.Event()

    def reader():
        while not done.is_set():
            assert q.shape == (arm.nq,) and np.isfinite(q.sum() + f.sum())

    def stepper():
        sim.step(400)
        done.set()

    run_threads(stepper, reader)
    assert sim.step_count == 400


def test_a_waiting_call_gets_its_turn_after_the_current_one(arm, tmp_path):
    """The lock is first come, first served: while one thread steps in a loop, another thread's
    call waits for the step call in progress (and at most one that started as it asked), not for
    a run of them. Counted in calls, not timed; the join is only a hang guard."""
    sim = driven(arm)
    path = tmp_path / "start.bin"
    fd.save_checkpoint(sim, path)
    done = [0]  # step calls the stepping thread has finished
    stop = threading.Event()
    waits, errors = [], []

    def stepper():
        try:
            # Calls long beside the scheduler's latency (about 12 ms each): the caller's turn is
            # counted in calls, and short ones let a loaded machine run several before the
            # caller even asks.
            while not stop.is_set():
                sim.step(4000)
                done[0] += 1
        except BaseException as e:  # noqa: B036 - reported below
            errors.append(e)

    def caller():
        try:
            while done[0] == 0:  # the stepper is in its loop
                threading.Event().wait(0.001)
            for _ in range(30):
                before = done[0]
                fd.load_checkpoint(path, sim)
                waits.append(done[0] - before)
        except BaseException as e:  # noqa: B036 - reported below
            errors.append(e)
        finally:
            stop.set()

    threads = [threading.Thread(target=stepper), threading.Thread(target=caller)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "hang"
    if errors:
        raise errors[0]
    assert len(waits) == 30
    assert max(waits) <= 2, waits
