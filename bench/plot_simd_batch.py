"""The benchmarks of Batch's SIMD lanes in featherdrive_bench's JSON (simd_batch/<robot>/<engine>/
envs:<N>/threads:<T>): a Markdown table of environment-steps per second and a plot. docs/benchmarks.md."""
import argparse
import json

ENGINES = ["batch", "simd_sse2", "simd_avx2", "simd_avx512", "mujoco"]
LABELS = {"batch": "scalar Batch", "simd_sse2": "SIMD SSE2", "simd_avx2": "SIMD AVX2",
          "simd_avx512": "SIMD AVX-512", "mujoco": "MuJoCo mj_step"}


def load(path):
    """{(robot, engine, envs, threads): env-steps per second} by wall time and by the calling
    thread's CPU time (the rate per core when the machine is shared), medians of repetitions."""
    with open(path) as f:
        data = json.load(f)
    rates, cpu_rates, errors = {}, {}, {}
    for b in data["benchmarks"]:
        name = b.get("run_name", b["name"])
        parts = name.split("/")
        if parts[0] != "simd_batch":
            continue
        key = (parts[1], parts[2], int(parts[3].split(":")[1]), int(parts[4].split(":")[1]))
        if b.get("error_occurred"):
            errors[key] = b.get("error_message", "error")
            continue
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        rates[key] = b["env_steps_per_second"]
        # The counter is per wall second; the same steps per CPU second of the calling thread.
        cpu_rates[key] = b["env_steps_per_second"] * b["real_time"] / b["cpu_time"]
    return data.get("context", {}), rates, cpu_rates, errors


def fmt(x):
    return "-" if x is None else f"{x / 1e3:.0f}k" if x < 1e6 else f"{x / 1e6:.2f}M"


def table(rates, cpu_rates):
    robots = sorted({k[0] for k in rates}, key=lambda r: ["arm7", "chain16", "humanoid"].index(r)
                    if r in ["arm7", "chain16", "humanoid"] else 9)
    engines = [e for e in ENGINES if any(k[1] == e for k in rates)]
    simd = [e for e in engines if e.startswith("simd")]
    head = ("| robot | envs | threads | " + " | ".join(LABELS[e] for e in engines) +
            " | best SIMD / scalar (per CPU second) | 2 threads / 1 (best SIMD) |")
    out = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in robots:
        for n in sorted({k[2] for k in rates if k[0] == r}):
            for t in sorted({k[3] for k in rates if k[0] == r}):
                cells = [fmt(rates.get((r, e, n, t))) for e in engines]
                best = max((rates.get((r, e, n, t), 0.0) for e in simd), default=0.0)
                best_cpu = max((cpu_rates.get((r, e, n, t), 0.0) for e in simd), default=0.0)
                scalar = rates.get((r, "batch", n, t))
                scalar_cpu = cpu_rates.get((r, "batch", n, t))
                ratio = f"{best / scalar:.2f}" if scalar and best else "-"
                if t == 1 and scalar_cpu and best_cpu:
                    ratio += f" ({best_cpu / scalar_cpu:.2f})"
                best1 = max((rates.get((r, e, n, 1), 0.0) for e in simd), default=0.0)
                scale = f"{best / best1:.2f}" if t > 1 and best1 else ""
                out.append(f"| {r} | {n} | {t} | " + " | ".join(cells) + f" | {ratio} | {scale} |")
    return "\n".join(out)


def plot(rates, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    robots = [r for r in ["arm7", "chain16", "humanoid"] if any(k[0] == r for k in rates)]
    fig, axes = plt.subplots(1, len(robots), figsize=(5 * len(robots), 4), squeeze=False)
    for ax, r in zip(axes[0], robots):
        for i, e in enumerate(ENGINES):
            for t, style in ((1, "-"), (2, "--")):
                pts = sorted((k[2], v) for k, v in rates.items() if k[0] == r and k[1] == e
                             and k[3] == t)
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], style, marker="o",
                            color=f"C{i}", label=f"{LABELS[e]}, {t} thread{'s' if t > 1 else ''}")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_title(r)
        ax.set_xlabel("environments")
        ax.set_ylabel("environment-steps per second")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=80)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("json")
    parser.add_argument("--plot", help="a .png for the plot")
    args = parser.parse_args()
    context, rates, cpu_rates, errors = load(args.json)
    print(f"Host: {context.get('host_name', '?')}, {context.get('num_cpus', '?')} CPUs, "
          f"load average {context.get('load_avg', '?')}\n")
    print(table(rates, cpu_rates))
    for key, why in sorted(errors.items()):
        print(f"- {'/'.join(map(str, key))}: {why.splitlines()[0]}")
    if args.plot:
        plot(rates, args.plot)


if __name__ == "__main__":
    main()
