"""Ctrl-C interrupts a long step(): KeyboardInterrupt with the state of a whole number of steps.
Each case runs in a subprocess that sends itself SIGINT from a timer thread while stepping
2**31 - 1 steps (hours); the parent replays step_count steps and compares bit for bit. The
subprocess timeout only guards against a hang: nothing here measures time."""
import json
import os
import pathlib
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import featherdrive as fd
from conftest import driven, hexes

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARM = ROOT / "examples" / "arm7.urdf"

PRELUDE = f"""
import json, os, signal, sys, threading
import numpy as np
import featherdrive as fd

from conftest import driven

def interrupt_in(seconds):
    threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT)).start()

def report(**values):
    print(json.dumps(values), flush=True)
    os._exit(0)  # also ends a thread still stepping

model = fd.load_urdf({str(ARM)!r}).model
"""


def run(body):
    script = PRELUDE + textwrap.dedent(body)
    path = os.pathsep.join([os.path.dirname(fd.__file__), os.path.dirname(__file__)])
    env = dict(os.environ, PYTHONPATH=path)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, env=env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
@pytest.mark.parametrize("delay", [0.05, 0.3])
def test_ctrl_c_interrupts_a_simulation_step(arm, solver, delay):
    result = run(f"""
        sim = driven(model, {solver!r})
        sim.step(3)
        interrupt_in({delay})
        try:
            sim.step(2**31 - 1)
        except KeyboardInterrupt:
            report(steps=sim.step_count, time=sim.time.hex(), q=[x.hex() for x in sim.q],
                   f=[x.hex() for x in sim.drive_force])
        report(steps=-1)
        """)
    steps = result["steps"]
    assert 3 < steps < 2**31 - 1 + 3
    replay = driven(arm, solver)
    replay.step(steps)
    assert result["q"] == hexes(replay.q)
    assert result["f"] == hexes(replay.drive_force)
    assert result["time"] == replay.time.hex()


@pytest.mark.parametrize("num_threads", [1, 2])
def test_ctrl_c_interrupts_a_batch_step(arm, num_threads):
    result = run(f"""
        batch = fd.Batch(driven(model, "tgs"), 3)
        batch.num_threads = {num_threads}
        batch.set_q(np.linspace(-0.3, 0.3, 3 * model.nq).reshape(3, model.nq))
        interrupt_in(0.2)
        try:
            batch.step(2**31 - 1)
        except KeyboardInterrupt:
            report(steps=[batch.sim(i).step_count for i in range(3)],
                   q=[x.hex() for x in batch.q.ravel()])
        report(steps=[-1])
        """)
    steps = result["steps"]
    assert len(set(steps)) == 1 and 0 < steps[0] < 2**31 - 1  # every copy at the same step
    replay = fd.Batch(driven(arm, "tgs"), 3)
    replay.set_q(np.linspace(-0.3, 0.3, 3 * arm.nq).reshape(3, arm.nq))
    replay.step(steps[0])
    assert result["q"] == hexes(replay.q)


def test_ctrl_c_interrupts_a_wait_for_the_lock(arm):
    """The main thread waits for a simulation another thread is stepping (for hours): Ctrl-C
    still interrupts the wait, and the other thread's step is not disturbed."""
    result = run("""
        sim = driven(model, "pgs")
        q = sim.q
        start = np.array(q)
        stepper = threading.Thread(target=sim.step, args=(2**31 - 1,), daemon=True)
        stepper.start()
        while np.array_equal(q, start):  # the stepper holds the lock once q moves
            pass
        interrupt_in(0.1)
        try:
            sim.set_q(np.zeros(model.nq))
        except KeyboardInterrupt:
            report(interrupted=True, stepping=stepper.is_alive(), moved=bool(np.any(q != 0)))
        report(interrupted=False)
        """)
    assert result == {"interrupted": True, "stepping": True, "moved": True}


def test_a_signal_handler_error_propagates(arm):
    """Whatever a Python signal handler raises comes out of step(), state whole."""
    result = run("""
        class Stop(Exception):
            pass
        def handler(signum, frame):
            raise Stop()
        signal.signal(signal.SIGINT, handler)
        sim = driven(model, "tgs")
        interrupt_in(0.1)
        try:
            sim.step(2**31 - 1)
        except Stop:
            report(steps=sim.step_count, q=[x.hex() for x in sim.q])
        report(steps=-1)
        """)
    replay = driven(arm, "tgs")
    replay.step(result["steps"])
    assert result["steps"] > 0 and result["q"] == hexes(replay.q)
