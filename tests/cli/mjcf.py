#!/usr/bin/python3
"""MJCF robots through the command: info and simulate take them as they take URDF.

usage: mjcf.py FEATHERDRIVE SOURCE_DIR OUT_DIR
"""
import csv
import os
import shutil
import sys

from commands import check, failures, one_line_error, run

HUMANOID = "/usr/share/mujoco/model/humanoid/humanoid.xml"


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def read(path):
    with open(path) as f:
        return f.read()


# A tetrahedron with outward faces (MuJoCo computes its volume and inertia).
TETRA_OBJ = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def files_a_model_reads(cli, work):
    """Every file an MJCF run reads, however reached (an include, a mesh), is an input no output
    may replace; a FIFO or folder where a file is named is refused without opening it."""
    os.makedirs(os.path.join(work, "meshes"))
    mesh = write(os.path.join(work, "meshes", "tetra.obj"), TETRA_OBJ)
    inc = write(os.path.join(work, "arm.xml"), """<mujocoinclude>
  <body name="link"><joint name="hinge" axis="0 1 0"/><geom size="0.05" mass="1" contype="0" conaffinity="0"/>
    <geom type="mesh" mesh="tetra" contype="0" conaffinity="0"/></body>
</mujocoinclude>
""")
    top = write(os.path.join(work, "top.xml"), """<mujoco model="inc">
  <compiler meshdir="meshes"/>
  <asset><mesh name="tetra" file="tetra.obj"/></asset>
  <worldbody><include file="arm.xml"/></worldbody>
</mujoco>
""")
    scene = write(os.path.join(work, "top.yaml"), "model: top.xml\nsteps: 5\n")
    before = {p: read(p) for p in (inc, mesh)}
    r = run(cli, "simulate", scene, "--steps", "3")
    check(r.returncode == 0, "simulate a scene whose MJCF includes a file and a mesh", r)
    for target, what in ((inc, "the included file"), (mesh, "the mesh file")):
        for option in ("--out", "--save-state"):
            r = run(cli, "simulate", scene, option, target)
            one_line_error(r, 2, f"{option} {target}: is a file the model reads")
            check(read(target) == before[target], f"simulate {option} onto {what} leaves it", r)
        r = run(cli, "translate", top, "--to", "physx", "--out", target)
        one_line_error(r, 2, f"--out {target}: is a file the model reads")
        check(read(target) == before[target], f"translate --out onto {what} leaves it", r)

    # A FIFO or a folder where MuJoCo would open a file: refused, not opened (a FIFO would hang).
    fifo = os.path.join(work, "fifo.xml")
    os.mkfifo(fifo)
    bad_include = write(os.path.join(work, "fifo_include.xml"),
                        '<mujoco><worldbody><include file="fifo.xml"/></worldbody></mujoco>\n')
    one_line_error(run(cli, "info", bad_include), 2,
                   f"{bad_include}: line 1: <include> {fifo}: is not a regular file (a FIFO)")
    os.mkfifo(os.path.join(work, "meshes", "fifo.obj"))
    bad_mesh = write(os.path.join(work, "fifo_mesh.xml"), """<mujoco><compiler meshdir="meshes/"/>
<asset><mesh name="m" file="fifo.obj"/></asset>
<worldbody><body><joint/><geom type="mesh" mesh="m"/></body></worldbody></mujoco>
""")
    one_line_error(run(cli, "info", bad_mesh), 2,
                   f"{bad_mesh}: line 2: <mesh> file '{work}/meshes/fifo.obj' is not a regular "
                   "file")
    dir_texture = write(os.path.join(work, "dir_texture.xml"), """<mujoco>
<asset><texture name="t" type="2d" file="meshes"/></asset>
<worldbody><body><joint/><geom size="0.1"/></body></worldbody></mujoco>
""")
    one_line_error(run(cli, "info", dir_texture), 2,
                   f"{dir_texture}: line 2: <texture> file '{work}/meshes' is a directory")

    # Nesting through includes: 60 files of 90 nested bodies (5 400 deep) would overflow MuJoCo's
    # compiler stack; the whole document's depth is bounded before it runs.
    for k in range(60):
        bodies = "".join(f'<body name="b{k}_{i}"><joint/><geom size="0.1"/>' for i in range(90))
        more = f'<include file="deep{k + 1}.xml"/>' if k < 59 else ""
        text = bodies + more + "</body>" * 90
        write(os.path.join(work, f"deep{k}.xml"),
              f"<mujoco><worldbody>{text}</worldbody></mujoco>\n" if k == 0
              else f"<mujocoinclude>{text}</mujocoinclude>\n")
    deep = os.path.join(work, "deep0.xml")
    one_line_error(run(cli, "info", deep), 2,
                   f"{deep}: {work}/deep11.xml, line 1: elements nested deeper than 1000 with "
                   "includes followed (the bound)")


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
    check("featherdrive: warning: 142 pairs of the robot's own geoms collide in MuJoCo" in r.stderr, "the self-collision warning", r)
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

    work = os.path.join(out_dir, "mjcf_files")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    files_a_model_reads(cli, os.path.abspath(work))

    for f in failures:
        print("FAIL:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
