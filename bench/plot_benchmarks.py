#!/usr/bin/python3
"""The tables and the plot of docs/benchmarks.md from featherdrive_bench's JSON output.

    ./build-bench/bench/featherdrive_bench --benchmark_repetitions=5 \\
        --benchmark_report_aggregates_only=true --benchmark_out=bench.json --benchmark_out_format=json
    /usr/bin/python3 bench/plot_benchmarks.py bench.json [--plot docs/benchmarks_per_dof.png]

Prints the Markdown tables (medians of the repetitions; CPU time for the single-thread
benchmarks, wall time for the batch) and the targets of issue 8, and writes the plot of time per
dof against N for every engine on the N-link chain.
"""

import argparse
import json
import sys

ENGINES = [
    ("featherdrive_pgs", "featherdrive PGS 4/1"),
    ("featherdrive_tgs", "featherdrive TGS 4/1"),
    ("mujoco_euler", "MuJoCo 2.2.2 Euler"),
    ("mujoco_implicit", "MuJoCo 2.2.2 implicit"),
    ("bullet", "Bullet 3.24 btMultiBody"),
    ("prototype_pgs", "chain prototype PGS 4/1"),  # bench/chain_prototype.hpp, chains only
]
KERNELS = ["kinematics", "aba", "articulated_response", "sweep"]


def load(path):
    with open(path) as f:
        data = json.load(f)
    medians, errors = {}, {}
    for b in data["benchmarks"]:
        name = b.get("run_name", b["name"])
        if b.get("error_occurred"):
            errors[name] = b.get("error_message", "error")
            continue
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        medians[name] = b
    return data.get("context", {}), medians, errors


def us(b, wall=False):
    scale = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}[b.get("time_unit", "ns")]
    return (b["real_time"] if wall else b["cpu_time"]) * scale


def fmt(x, digits=3):
    if x is None:
        return "—"
    if x >= 100:
        return f"{x:.0f}"
    return f"{x:.{digits}g}"


def robots_of(medians, errors):
    names = []
    for key in list(medians) + list(errors):
        parts = key.split("/")
        if parts[0] == "step" and parts[1] not in names:
            names.append(parts[1])
    chains = sorted([n for n in names if n.startswith("chain")], key=lambda n: int(n[5:]))
    return chains + [n for n in names if not n.startswith("chain")]


def step_tables(medians, errors):
    robots = robots_of(medians, errors)
    out = []
    head = "| robot | dofs | " + " | ".join(label for _, label in ENGINES) + " |"
    out.append("Microseconds per step (median CPU time):\n")
    out.append(head)
    out.append("|" + "---|" * (len(ENGINES) + 2))
    for r in robots:
        row, dofs = [], None
        for key, _ in ENGINES:
            b = medians.get(f"step/{r}/{key}")
            if b:
                dofs = int(b.get("dofs", 0))
            row.append(fmt(us(b)) if b else ("n/a" if f"step/{r}/{key}" in errors else "—"))
        out.append(f"| {r} | {dofs} | " + " | ".join(row) + " |")
    out.append("\nMicroseconds per dof per step:\n")
    out.append(head)
    out.append("|" + "---|" * (len(ENGINES) + 2))
    for r in robots:
        row, dofs = [], None
        for key, _ in ENGINES:
            b = medians.get(f"step/{r}/{key}")
            if b:
                dofs = int(b.get("dofs", 0))
                row.append(fmt(us(b) / dofs))
            else:
                row.append("n/a" if f"step/{r}/{key}" in errors else "—")
        out.append(f"| {r} | {dofs} | " + " | ".join(row) + " |")
    out.append("\nPeer time / featherdrive time, same robot, same run (above 1: featherdrive is faster):\n")
    peers = [(k, l) for k, l in ENGINES if not k.startswith("featherdrive")]
    out.append("| robot | " + " | ".join(f"{l} / PGS" for _, l in peers) + " | "
               + " | ".join(f"{l} / TGS" for _, l in peers) + " |")
    out.append("|" + "---|" * (2 * len(peers) + 1))
    for r in robots:
        cells = []
        for ours in ("featherdrive_pgs", "featherdrive_tgs"):
            o = medians.get(f"step/{r}/{ours}")
            for key, _ in peers:
                p = medians.get(f"step/{r}/{key}")
                cells.append(f"{us(p) / us(o):.2f}" if (o and p) else "n/a")
        out.append(f"| {r} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def kernel_table(medians):
    robots = []
    for key in medians:
        parts = key.split("/")
        if parts[0] == "kernel" and parts[1] not in robots:
            robots.append(parts[1])
    chains = sorted([n for n in robots if n.startswith("chain")], key=lambda n: int(n[5:]))
    robots = chains + [n for n in robots if not n.startswith("chain")]
    out = ["Kernels, microseconds per call (nanoseconds per dof):\n",
           "| robot | dofs | " + " | ".join(KERNELS) + " |", "|" + "---|" * (len(KERNELS) + 2)]
    for r in robots:
        cells, dofs = [], None
        for k in KERNELS:
            b = medians.get(f"kernel/{r}/{k}")
            if b:
                dofs = int(b.get("dofs", 0))
                cells.append(f"{fmt(us(b))} ({us(b) * 1e3 / dofs:.0f})")
            else:
                cells.append("—")
        out.append(f"| {r} | {dofs} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def batch_rows(medians):
    rows = []
    for key, b in medians.items():
        if key.startswith("batch/"):
            rows.append((int(b.get("threads", 0)), b["robot_steps_per_second"], us(b, wall=True)))
    return sorted(rows)


def batch_table(medians):
    rows = batch_rows(medians)
    out = ["Batch of 64 independent arm7 simulations sharing one Model (TBB parallel_for, PGS 4/1):\n",
           "| threads | robot-steps per second | wall time per batch of 640 steps (us) |", "|---|---|---|"]
    for threads, rate, t in rows:
        out.append(f"| {threads} | {rate:,.0f} | {fmt(t)} |")
    return "\n".join(out)


def targets(medians):
    lines = ["Targets of issue 8:\n"]

    def per_dof(r, e):
        b = medians.get(f"step/{r}/{e}")
        return us(b) / int(b["dofs"]) if b else None

    for e, label in ENGINES[:2]:
        a, b = per_dof("chain16", e), per_dof("chain1024", e)
        if a and b:
            ok = "reached" if b / a <= 1.3 else "NOT reached"
            lines.append(f"- O(n), {label}: per dof at N = 1024 / at N = 16 = {b / a:.2f} "
                         f"(target <= 1.3): {ok}")
    a = per_dof("chain256", "featherdrive_pgs")
    if a:
        ok = "reached" if a <= 0.15 else "NOT reached"
        lines.append(f"- Absolute, PGS 4/1 at N = 256: {a:.3f} us per dof (target <= 0.15): {ok}")
    for r in ("chain16", "arm7"):
        o, p = medians.get(f"step/{r}/featherdrive_pgs"), medians.get(f"step/{r}/mujoco_euler")
        if o and p:
            ratio = us(p) / us(o)
            ok = "reached" if ratio >= 2.0 else "NOT reached"
            lines.append(f"- {r}: MuJoCo Euler / featherdrive PGS = {ratio:.2f} (target >= 2): {ok}")
    rows = batch_rows(medians)
    if len(rows) >= 2:
        ratio = rows[-1][1] / rows[0][1]
        ok = "reached" if ratio >= 1.8 else "NOT reached"
        lines.append(f"- Batch: {rows[-1][0]} cores / 1 core = {ratio:.2f} (target >= 1.8): {ok}")
    return "\n".join(lines)


def plot(medians, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    markers = ["o", "s", "^", "v", "D", "x"]
    for (key, label), marker in zip(ENGINES, markers):
        xs, ys = [], []
        for name, b in medians.items():
            parts = name.split("/")
            if parts[0] == "step" and parts[1].startswith("chain") and parts[2] == key:
                n = int(b["dofs"])
                xs.append(n)
                ys.append(us(b) / n)
        if xs:
            order = sorted(range(len(xs)), key=lambda k: xs[k])
            ax.plot([xs[k] for k in order], [ys[k] for k in order], marker=marker, label=label)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("N (links = dofs of the spatial chain)")
    ax.set_ylabel("microseconds per dof per step")
    ax.set_title("Step time per dof, N-link chain, drives on every joint")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("json")
    parser.add_argument("--plot", help="PNG to write (time per dof against N)")
    args = parser.parse_args()
    context, medians, errors = load(args.json)
    print(f"Host: {context.get('host_name', '?')}, {context.get('num_cpus', '?')} CPUs at "
          f"{context.get('mhz_per_cpu', '?')} MHz, load average {context.get('load_avg', '?')}\n")
    print(step_tables(medians, errors))
    print()
    print(kernel_table(medians))
    print()
    print(batch_table(medians))
    print()
    print(targets(medians))
    if errors:
        print("\nBenchmarks that could not run:")
        for name, why in sorted(errors.items()):
            print(f"- {name}: {why.splitlines()[0]}")
    if args.plot:
        plot(medians, args.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
