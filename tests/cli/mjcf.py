#!/usr/bin/python3
"""MJCF robots through the command: info and simulate take them as they take URDF.

usage: mjcf.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import csv
import os
import sys

from commands import check, failures, run

HUMANOID = "/usr/share/mujoco/model/humanoid/humanoid.xml"


def main():
    cli, source, out_dir = sys.argv[1:4]
    os.makedirs(out_dir, exist_ok=True)

    r = run(cli, "info", HUMANOID)
    check(r.returncode == 0, "info humanoid succeeds", r)
    # The file: 21 hinges, torso welded by default; 21 motors, right_hip_y with gear 120.
    for text in ("robot 'Humanoid'", "21 dofs", "fixed base",
                 "- torso  (root, welded to the world)", "MJCF actuators (21):",
                 "right_hip_y: motor on right_hip_y, gain 1, gear 120"):
        check(text in r.stdout, f"info humanoid shows {text!r}", r)
    check("featherdrive: warning: contacts are not simulated" in r.stderr, "the contact warning", r)
    r = run(cli, "info", HUMANOID, "--floating")
    check(r.returncode == 0 and "27 dofs" in r.stdout and "floating base" in r.stdout,
          "info --floating: the free joint", r)

    r = run(cli, "info", os.path.join(out_dir, "no_such_robot.xml"))
    check(r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
          and "no_such_robot.xml: cannot open" in r.stderr,
          "a missing MJCF file: exit 2, one line", r)

    out = os.path.join(out_dir, "humanoid_hold.csv")
    r = run(cli, "simulate", os.path.join(source, "examples", "humanoid_hold.yaml"),
            "--steps", "40", "--out", out)
    check(r.returncode == 0 and "right_shoulder1" in r.stdout, "simulate humanoid_hold", r)
    if r.returncode == 0:
        with open(out, newline="") as f:
            rows = list(csv.reader(f))
        check(len(rows) == 42 and "q:abdomen_z" in rows[0] and "f:left_elbow" in rows[0],
              f"the CSV has 41 rows and the MJCF joint names: {rows[0][:4]}")

    for f in failures:
        print("FAIL:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
