#!/usr/bin/python3
"""--save-state / --load-state: a run interrupted by a checkpoint and resumed writes the same CSV
rows, text for text (numbers in shortest round-trip form, so bit for bit), and ends in the same
checkpoint bytes as the uninterrupted run; bad checkpoints exit 2 with one line saying why.

usage: checkpoint.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import os
import subprocess
import sys

failures = []


def run(*args):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=120)


def check(condition, what, result=None):
    if not condition:
        detail = f"\n  rc={result.returncode} stdout={result.stdout!r} stderr={result.stderr!r}" if result else ""
        failures.append(what + detail)


def one_line_error(result, code, text):
    check(result.returncode == code, f"exit code {code} for {text!r}", result)
    check(len(result.stderr.strip().splitlines()) == 1, f"one stderr line for {text!r}", result)
    check(text in result.stderr, f"stderr holds {text!r}", result)


def rows(path):
    with open(path) as f:
        return f.read().splitlines()


def resume_case(cli, scene, out_dir, tag, total, split):
    p = lambda name: os.path.join(out_dir, f"{tag}_{name}")  # noqa: E731
    r = run(cli, "simulate", scene, "--steps", str(total), "--out", p("whole.csv"),
            "--save-state", p("whole.ckpt"))
    check(r.returncode == 0, f"{tag}: the uninterrupted run", r)
    r = run(cli, "simulate", scene, "--steps", str(split), "--out", p("first.csv"),
            "--save-state", p("split.ckpt"))
    check(r.returncode == 0, f"{tag}: the first part", r)
    check(f"state: {p('split.ckpt')}" in r.stdout, f"{tag}: the summary names the state file", r)
    r = run(cli, "simulate", scene, "--steps", str(total - split), "--load-state", p("split.ckpt"),
            "--out", p("second.csv"), "--save-state", p("resumed.ckpt"))
    check(r.returncode == 0, f"{tag}: the resumed part", r)
    check(f"resumed from {p('split.ckpt')} at step {split}" in r.stdout, f"{tag}: the summary says resumed", r)
    if failures:
        return
    whole, first, second = rows(p("whole.csv")), rows(p("first.csv")), rows(p("second.csv"))
    check(len(whole) == total + 2, f"{tag}: {total + 1} rows and a header")
    check(first == whole[:split + 2], f"{tag}: the first part equals the uninterrupted rows 0..{split}")
    check(second[0] == whole[0], f"{tag}: the resumed CSV has the same header")
    check(second[1:] == whole[split + 1:],
          f"{tag}: the resumed CSV equals the uninterrupted rows {split}..{total}")
    check(second[1].startswith(f"{split},"), f"{tag}: the resumed CSV starts at step {split}: {second[1]!r}")
    with open(p("whole.ckpt"), "rb") as a, open(p("resumed.ckpt"), "rb") as b:
        check(a.read() == b.read(), f"{tag}: the final checkpoints are identical")
    leftovers = [f for f in os.listdir(out_dir) if f.startswith(f".{tag}_")]
    check(leftovers == [], f"{tag}: no temporary checkpoint files left: {leftovers}")


def main():
    cli, source, out_dir = sys.argv[1:4]
    out_dir = os.path.join(out_dir, "checkpoint")
    os.makedirs(out_dir, exist_ok=True)
    ex = lambda name: os.path.join(source, "examples", name)  # noqa: E731

    # Sine targets under TGS, and a floating chain under PGS with joint settings.
    resume_case(cli, ex("chain3.yaml"), out_dir, "chain3", 30, 12)
    floating = os.path.join(out_dir, "floating.yaml")
    with open(floating, "w") as f:
        f.write(f"model: {ex('chain3.urdf')}\nfixed_base: false\ndt: 0.01\nsteps: 5\n"
                "solver: {type: pgs, position_iterations: 3, velocity_iterations: 2}\n"
                "initial: {qd: {joint1: 0.7}}\n"
                "drive_defaults: {type: force, stiffness: 50, damping: 2}\n"
                "drives: {joint2: {target: {sine: {amplitude: 0.3, frequency: 1.5}}}}\n"
                "joints: {joint1: {lower: -0.4, upper: 0.4, max_velocity: 1.5,"
                " friction: {static: 0.2, dynamic: 0.1, viscous: 0.05}}}\n")
    resume_case(cli, floating, out_dir, "floating", 25, 9)

    ckpt = os.path.join(out_dir, "chain3_split.ckpt")
    if os.path.exists(ckpt):
        with open(ckpt, "rb") as f:
            data = f.read()
        cut = os.path.join(out_dir, "cut.ckpt")
        with open(cut, "wb") as f:
            f.write(data[:-10])
        one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--load-state", cut), 2,
                       f"{cut}: truncated checkpoint: the header announces {len(data)} bytes, "
                       f"the file has {len(data) - 10}")
        flipped = os.path.join(out_dir, "flipped.ckpt")
        with open(flipped, "wb") as f:
            f.write(data[:60] + bytes([data[60] ^ 1]) + data[61:])
        one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--load-state", flipped), 2,
                       f"{flipped}: corrupt checkpoint: checksum")
        one_line_error(run(cli, "simulate", ex("slider.yaml"), "--load-state", ckpt), 2,
                       f"{ckpt}: the checkpoint is of a different model (nq 3, nv 3")
        # The same URDF with a floating base is another model too.
        one_line_error(run(cli, "simulate", floating, "--load-state", ckpt), 2,
                       "the checkpoint is of a different model")
    one_line_error(run(cli, "simulate", ex("chain3.yaml"), "--load-state",
                       os.path.join(out_dir, "missing.ckpt")), 2, "missing.ckpt: cannot open the checkpoint")
    r = run(cli, "simulate", ex("chain3.yaml"), "--steps", "1", "--save-state",
            os.path.join(out_dir, "no-such-folder", "s.ckpt"))
    check(r.returncode == 1 and "cannot write the checkpoint" in r.stderr,
          "an unwritable --save-state exits 1", r)

    if failures:
        for f in failures:
            print("FAIL:", f)
        sys.exit(1)
    print("ok")


if __name__ == "__main__":
    main()
