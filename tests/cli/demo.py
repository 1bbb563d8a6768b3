#!/usr/bin/python3
"""What `make run` does: the arm7 demo scenes under PGS and TGS with --plot. Each must succeed,
write a trajectory with one row per step plus the initial state, print its summary and write a
non-empty PNG.

usage: demo.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import csv
import os
import subprocess
import sys


def main():
    cli, source, out_dir = sys.argv[1:4]
    os.makedirs(out_dir, exist_ok=True)
    for solver in ("pgs", "tgs"):
        scene = os.path.join(source, "examples", f"arm7_{solver}.yaml")
        png = os.path.join(out_dir, f"arm7_{solver}.png")
        out = os.path.join(out_dir, f"arm7_{solver}.csv")
        if os.path.exists(png):
            os.remove(png)
        run = subprocess.run([cli, "simulate", scene, "--out", out, "--plot", png],
                             capture_output=True, text=True, timeout=300)
        if run.returncode != 0:
            sys.exit(f"FAIL: {solver}: exit {run.returncode}: {run.stderr}")
        for needed in ("joint1", "joint7", "final error", "steps/s", "plot: " + png):
            if needed not in run.stdout:
                sys.exit(f"FAIL: {solver}: the summary lacks {needed!r}:\n{run.stdout}")
        with open(png, "rb") as f:
            head = f.read(8)
        if head != b"\x89PNG\r\n\x1a\n" or os.path.getsize(png) < 10000:
            sys.exit(f"FAIL: {png} is not a plot ({os.path.getsize(png)} bytes)")
        with open(out, newline="") as f:
            rows = list(csv.reader(f))
        # step, t, then q, qd, f, target and target_velocity of each of the 7 driven joints
        if len(rows) != 1 + 361 or len(rows[0]) != 2 + 5 * 7:
            sys.exit(f"FAIL: {out}: {len(rows)} rows of {len(rows[0])} columns")
        print(run.stdout)


if __name__ == "__main__":
    main()
