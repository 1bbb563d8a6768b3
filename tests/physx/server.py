#!/usr/bin/env python3
"""Starts or stops the PhysX harness's server for the test run (ctest fixture physx_server).

  server.py start NODE HARNESS_DIR SOCKET   starts `node harness.js --serve SOCKET` in its own
                                            session and returns once the socket answers
  server.py stop SOCKET                     stops it (it also exits by itself when idle)

The parity tests find it through $FEATHERDRIVE_PHYSX_SERVER; without it they start node per run,
so a server that failed to start costs time, not results.
"""
import os
import signal
import socket
import subprocess
import sys
import time

IDLE_SECONDS = "300"


def answers(path):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        s.connect(path)
        return True
    except OSError:
        return False
    finally:
        s.close()


def start(node, harness_dir, path):
    stop(path)
    log = open(path + ".log", "w")
    # Its own session and no inherited pipes: ctest does not wait for it.
    proc = subprocess.Popen([node, os.path.join(harness_dir, "harness.js"), "--serve", path,
                             IDLE_SECONDS], stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                            start_new_session=True)
    with open(path + ".pid", "w") as f:
        f.write(str(proc.pid))
    for _ in range(600):  # up to 60 s for PhysX to load
        if proc.poll() is not None:
            sys.exit(f"server.py: the harness's server exited with {proc.returncode} (see {path}.log)")
        if answers(path):
            print(f"server.py: PhysX harness serving on {path} (pid {proc.pid})")
            return
        time.sleep(0.1)
    proc.kill()
    sys.exit("server.py: the harness's server did not answer within 60 s")


def stop(path):
    try:
        with open(path + ".pid") as f:
            pid = int(f.read())
        with open(f"/proc/{pid}/cmdline", "rb") as f:  # still ours, not a reused pid
            if b"--serve" in f.read():
                os.kill(pid, signal.SIGTERM)
    except (OSError, ValueError):
        pass
    for leftover in (path, path + ".pid"):
        try:
            os.remove(leftover)
        except OSError:
            pass


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "start":
        start(*sys.argv[2:])
    elif len(sys.argv) == 3 and sys.argv[1] == "stop":
        stop(sys.argv[2])
    else:
        sys.exit(__doc__)
