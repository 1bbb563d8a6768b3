#!/usr/bin/python3
"""Plots featherdrive - PhysX over time per joint: position, velocity and force differences.
Called by `featherdrive compare-physx --plot`.

usage: plot_physx_diff.py [--title TITLE] [--] DIFFERENCES.csv OUT.png
DIFFERENCES.csv: step,t,dq:<joint>...,dqd:<joint>...,df:<joint>...
"""
import argparse
import csv
import sys

try:
    import matplotlib
    from plot_layout import stacked_axes
except ImportError as e:  # one line for featherdrive to show, not a traceback
    sys.exit(f"plot_physx_diff: {sys.executable} cannot import matplotlib ({e}); "
             "Debian: apt-get install python3-matplotlib, or set FEATHERDRIVE_PYTHON")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("differences")
    parser.add_argument("png")
    parser.add_argument("--title", default="featherdrive - PhysX")
    args = parser.parse_args()

    with open(args.differences, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        sys.exit(f"plot_physx_diff: {args.differences} has no rows")
    header, data = rows[0], rows[1:]
    col = {name: [float(r[i]) for r in data] for i, name in enumerate(header)}
    joints = [c[3:] for c in header if c.startswith("dq:")]

    panels = (("dq:", "q difference [rad or m]"), ("dqd:", "qd difference [rad/s or m/s]"),
              ("df:", "force difference [Nm or N]"))
    fig, axes = stacked_axes(len(panels), args.title)
    colours = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (prefix, label) in zip(axes, panels):
        for i, joint in enumerate(joints):
            ax.plot(col["t"], col[prefix + joint], color=colours[i % len(colours)], label=joint,
                    linewidth=0.9)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        # Differences near float32 rounding: keep matplotlib from hiding them in an offset.
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3), useOffset=False)
    axes[0].legend(loc="upper right", fontsize="small", ncol=2)
    axes[-1].set_xlabel("t [s]")
    fig.savefig(args.png, dpi=100, format="png")  # the name may be a temporary one


if __name__ == "__main__":
    main()
