#!/usr/bin/python3
"""A malformed input must give exit code 2 and one line on stderr holding the text in
NAME.expected (line 1) and naming the file (NAME itself, or the file after "file: " on line 2).

usage: check_malformed.py FEATHERDRIVE INPUT
"""
import os
import subprocess
import sys


def main():
    cli, path = sys.argv[1], sys.argv[2]
    with open(path + ".expected") as f:
        lines = f.read().splitlines()
    expected = lines[0]
    named = os.path.basename(path)
    for line in lines[1:]:
        if line.startswith("file: "):
            named = line[len("file: "):]
    # A scene is refused alike by simulate and by check (which also runs the scene's targets).
    commands = ([["info", path]] if path.endswith((".urdf", ".xml"))
                else [["simulate", path, "--steps", "2"], ["check", path]])
    for command in commands:
        stderr = run_one([cli] + command, expected, named)
    print("ok:", stderr)


def run_one(args, expected, named):
    run = subprocess.run(args, capture_output=True, text=True, timeout=60)
    errors = []
    if run.returncode != 2:
        errors.append(f"exit code {run.returncode}, expected 2")
    stderr = run.stderr.rstrip("\n")
    if len(stderr.splitlines()) != 1:
        errors.append(f"stderr has {len(stderr.splitlines())} lines, expected 1")
    if not stderr.startswith("featherdrive: "):
        errors.append("stderr does not start with 'featherdrive: '")
    if expected not in stderr:
        errors.append(f"stderr lacks {expected!r}")
    if named not in stderr:
        errors.append(f"stderr does not name {named!r}")
    if run.stdout:
        errors.append(f"stdout is not empty: {run.stdout!r}")
    if errors:
        print(f"{' '.join(args)}\nstderr: {run.stderr!r}")
        for e in errors:
            print("FAIL:", e)
        sys.exit(1)
    return stderr
    print("ok:", stderr)


if __name__ == "__main__":
    main()
