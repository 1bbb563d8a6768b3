#!/usr/bin/python3
"""Plots a featherdrive trajectory: joint positions against their drive targets, the tracking
error and the drive forces. Called by `featherdrive simulate --plot`.

usage: plot_trajectory.py [--title TITLE] [--] TRAJECTORY.csv TARGETS.csv OUT.png
(`--` lets a path begin with "-"; OUT.png is written as a PNG whatever its name.)
"""
import argparse
import csv
import sys

try:
    import matplotlib
    from plot_layout import stacked_axes
except ImportError as e:  # one line for featherdrive to show, not a traceback
    sys.exit(f"plot_trajectory: {sys.executable} cannot import matplotlib ({e}); "
             "Debian: apt-get install python3-matplotlib, or set FEATHERDRIVE_PYTHON")


def read_columns(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        sys.exit(f"plot_trajectory: {path} is empty")
    header, data = rows[0], rows[1:]
    return {name: [float(r[i]) for r in data] for i, name in enumerate(header)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trajectory")
    parser.add_argument("targets")
    parser.add_argument("png")
    parser.add_argument("--title", default="featherdrive")
    args = parser.parse_args()

    traj = read_columns(args.trajectory)
    targets = read_columns(args.targets)
    t = traj["t"]
    driven = [c[len("target:"):] for c in targets if c.startswith("target:")]
    joints = driven or [c[2:] for c in traj if c.startswith("q:")]

    fig, (ax_q, ax_e, ax_f) = stacked_axes(3, args.title)
    colours = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, joint in enumerate(joints):
        colour = colours[i % len(colours)]
        q = traj["q:" + joint]
        ax_q.plot(t, q, color=colour, label=joint)
        if joint in driven:
            target = targets["target:" + joint]
            ax_q.plot(targets["t"], target, color=colour, linestyle="--", linewidth=0.8)
            ax_e.plot(t, [a - b for a, b in zip(target, q)], color=colour, label=joint)
        if "f:" + joint in traj:  # a floating root's q columns have no force column
            ax_f.plot(t, traj["f:" + joint], color=colour, label=joint)
    ax_q.set_ylabel("position (solid) / target (dashed)")
    ax_e.set_ylabel("tracking error target - q")
    ax_f.set_ylabel("drive force [N or Nm]")
    ax_f.set_xlabel("t [s]")
    ax_q.legend(loc="upper right", fontsize="small", ncol=2)
    for ax in (ax_q, ax_e, ax_f):
        ax.grid(True, alpha=0.3)
    fig.savefig(args.png, dpi=100, format="png")  # the name may be a temporary one


if __name__ == "__main__":
    main()
