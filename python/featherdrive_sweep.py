"""Tracking error over a grid of drive gains: ``featherdrive sweep`` and ``fd.sweep``.

Every grid point is one environment of a Batch that runs the scene with those gains; the error
of a drive is the RMS over the run of (target - q), as ``featherdrive simulate`` reports it.
Locally the whole grid is one Batch on all cores; with a Dask client the grid is cut into chunks
of rows, each shipped to a worker as (scene path, scene text, rows) and run there as a Batch, and
the results are gathered in grid order (featherdrive_distributed.map_ordered). Each environment
is bit-identical to a lone Simulation and the errors are reduced per point, so the numbers do not
depend on threads, chunks or workers. docs/fitting.md, "Sweeps and Dask".

Grid syntax: ``NAME=SPEC[,NAME=SPEC...]`` with NAME ``stiffness`` or ``damping`` and SPEC
``VALUE`` (one point), ``LO:HI:N`` (N points spaced linearly) or ``LO:HI:N:log`` (N points
spaced geometrically, LO > 0). The first name varies slowest.
"""

import argparse
import math
import os
import pathlib
import sys
import tempfile

import numpy as np

__all__ = ["sweep", "parse_grid", "SweepResult", "main"]

PARAMETERS = ("stiffness", "damping")


def _number(text, where):
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{where} = {text!r}: must be a number") from None
    if not math.isfinite(value) or value < 0.0:
        raise ValueError(f"{where} = {text!r}: must be finite and >= 0")
    return value


def _axis(name, spec):
    """The values of one grid axis from LO:HI:N[:log|:lin] or VALUE."""
    where = f"--grid {name}={spec}"
    parts = spec.split(":")
    if len(parts) == 1:
        return np.array([_number(parts[0], where)]), False
    if len(parts) not in (3, 4):
        raise ValueError(f"{where}: expected VALUE, LO:HI:N or LO:HI:N:log")
    lo, hi = _number(parts[0], where + " LO"), _number(parts[1], where + " HI")
    try:
        n = int(parts[2])
    except ValueError:
        raise ValueError(f"{where}: N = {parts[2]!r} must be a whole number of points") from None
    if n < 1 or n > 100_000:
        raise ValueError(f"{where}: N = {n} must be in [1, 100000]")
    if hi < lo:
        raise ValueError(f"{where}: HI = {parts[1]} is below LO = {parts[0]}")
    spacing = parts[3] if len(parts) == 4 else "lin"
    if spacing not in ("lin", "log"):
        raise ValueError(f"{where}: spacing {spacing!r} must be lin or log")
    if spacing == "log":
        if lo <= 0.0:
            raise ValueError(f"{where}: log spacing needs LO > 0, not {parts[0]}")
        return np.geomspace(lo, hi, n), True
    return np.linspace(lo, hi, n), False


def parse_grid(grid):
    """[(name, values, log)] from the grid text or a {name: values} mapping; ValueError naming
    the entry for bad syntax, an unknown or repeated name, or bad values."""
    if isinstance(grid, str):
        entries = []
        for item in grid.split(","):
            if "=" not in item:
                raise ValueError(f"--grid entry {item!r}: expected NAME=LO:HI:N[:log] "
                                 f"(NAME one of {', '.join(PARAMETERS)})")
            name, spec = (s.strip() for s in item.split("=", 1))
            entries.append((name, spec))
    elif isinstance(grid, dict):
        entries = list(grid.items())
    else:
        raise TypeError(f"grid must be a str or a dict, not {type(grid).__name__}")
    if not entries:
        raise ValueError("the grid is empty")
    axes, seen = [], set()
    for name, spec in entries:
        if name not in PARAMETERS:
            raise ValueError(f"--grid {name}: unknown parameter (expected one of "
                             f"{', '.join(PARAMETERS)})")
        if name in seen:
            raise ValueError(f"--grid {name}: given twice")
        seen.add(name)
        if isinstance(spec, str):
            values, log = _axis(name, spec)
        else:
            values = np.asarray(spec, dtype=float).ravel()
            if values.size == 0 or not np.all(np.isfinite(values)) or np.any(values < 0):
                raise ValueError(f"grid {name}: values must be finite, >= 0 and not empty")
            log = False
        axes.append((name, values, log))
    return axes


class SweepResult:
    """A sweep's grid and errors, rows in grid order (the first parameter slowest).

    names: the parameters; axes: their values; points (M, p): each point's values;
    joints: the drives' joints; rms (M, len(joints)): RMS of target - q per drive [rad or m];
    total (M,): sqrt(mean over the drives of rms**2); objective (M,): the --joint's rms, or
    total; diverged (M,): points whose run diverged (their errors are nan)."""

    def __init__(self, axes, joints, joint, rms, diverged):
        self.names = [a[0] for a in axes]
        self.axes = [a[1] for a in axes]
        self.log = [a[2] for a in axes]
        self.points = _points(axes)
        self.joints = list(joints)
        self.joint = joint
        self.rms = rms
        self.diverged = diverged
        self.total = np.array([math.sqrt(math.fsum(r * r for r in row) / len(row))
                               for row in rms])
        self.objective = rms[:, self.joints.index(joint)] if joint else self.total

    def best(self):
        """Index of the point with the least objective among those that did not diverge."""
        ok = np.flatnonzero(~self.diverged)
        if ok.size == 0:
            raise RuntimeError("every grid point diverged")
        return int(ok[np.argmin(self.objective[ok])])

    def write_csv(self, path):
        header = self.names + [f"rms:{j}" for j in self.joints] + ["rms_total", "diverged"]
        lines = [",".join(header)]
        for i in range(len(self.points)):
            values = list(self.points[i]) + list(self.rms[i]) + [self.total[i]]
            lines.append(",".join(repr(float(v)) for v in values)
                         + f",{int(self.diverged[i])}")
        _write_atomically(path, ("\n".join(lines) + "\n").encode())

    def plot(self, path, title):
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        what = f"RMS error of {self.joint}" if self.joint else "RMS error, all drives"
        fig, ax = plt.subplots(figsize=(7, 5.5))
        best = self.best()
        varying = [i for i, a in enumerate(self.axes) if len(a) > 1]
        if len(varying) <= 1:
            k = varying[0] if varying else 0
            ax.plot(self.points[:, k], self.objective, "o-")
            ax.plot(self.points[best, k], self.objective[best], "r*", markersize=14)
            ax.set_xlabel(self.names[k])
            ax.set_ylabel(what)
            if self.log[k]:
                ax.set_xscale("log")
        elif len(varying) == 2:
            z = np.ma.masked_invalid(self.objective.reshape(len(self.axes[0]),
                                                            len(self.axes[1])))
            mesh = ax.pcolormesh(_edges(self.axes[1], self.log[1]),
                                 _edges(self.axes[0], self.log[0]), z, shading="flat",
                                 norm=matplotlib.colors.LogNorm()
                                 if np.nanmin(self.objective) > 0 else None)
            fig.colorbar(mesh, ax=ax, label=what)
            ax.plot(self.points[best, 1], self.points[best, 0], "w*", markersize=14)
            ax.set_xlabel(self.names[1])
            ax.set_ylabel(self.names[0])
            if self.log[1]:
                ax.set_xscale("log")
            if self.log[0]:
                ax.set_yscale("log")
        else:
            raise ValueError(f"a plot shows one or two parameters, not {len(varying)}")
        ax.set_title(title)
        fig.tight_layout()
        with tempfile.NamedTemporaryFile(dir=os.path.dirname(os.path.abspath(path)),
                                         suffix=".png", delete=False) as tmp:
            pass
        try:
            fig.savefig(tmp.name, dpi=100)
            os.replace(tmp.name, path)
        finally:
            plt.close(fig)
            if os.path.exists(tmp.name):
                os.unlink(tmp.name)


def _edges(values, log):
    """Cell edges around grid values: midpoints, geometric ones on a log axis."""
    v = np.log(values) if log else np.asarray(values, dtype=float)
    mid = (v[1:] + v[:-1]) / 2
    edges = np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])
    return np.exp(edges) if log else edges


def _points(axes):
    mesh = np.meshgrid(*[a[1] for a in axes], indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def _write_atomically(path, data):
    folder = os.path.dirname(os.path.abspath(path))
    fd_, tmp = tempfile.mkstemp(dir=folder, prefix=".sweep-")
    try:
        with os.fdopen(fd_, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _drives(scene, joint):
    """The scene's implicit drives [(joint, dof)] and the dofs the grid changes."""
    import featherdrive as fd
    drives = [(d.joint, d.dof)
              for d in scene.drives if d.drive.type != fd.DriveType.none and d.actuator is None]
    if not drives:
        raise ValueError(f"{scene.path}: the scene has no implicit drive (type force or "
                         "acceleration) to sweep")
    names = [d[0] for d in drives]
    if joint is not None and joint not in names:
        raise ValueError(f"--joint {joint}: not an implicit drive of {scene.path} "
                         f"(its drives: {', '.join(names)})")
    changed = [d[1] for d in drives if joint is None or d[0] == joint]
    return drives, changed


def evaluate(item):
    """RMS errors (k, drives) and diverged flags (k,) of the rows of one chunk: item is
    (scene path, scene text, parameter names, rows (k, p), joint or None, threads). Module-level
    and of plain data, so that Dask ships it to workers."""
    import featherdrive as fd
    path, text, names, rows, joint, threads = item
    scene = fd.parse_scene(text, path)
    drives, changed = _drives(scene, joint)
    prototype = fd.make_simulation(scene)
    rows = np.atleast_2d(np.asarray(rows, dtype=float))
    batch = fd.Batch(prototype, len(rows))
    batch.num_threads = threads
    for i, row in enumerate(rows):
        env = batch.sim(i)
        for dof in changed:
            drive = env.drive(dof)
            for name, value in zip(names, row):
                setattr(drive, name, float(value))
            env.set_drive(dof, drive)
    # The scene's targets, the same for every environment: a reference simulation takes them
    # from fd.apply_targets (control steps and interpolation included) for set_drive_targets.
    reference = fd.make_simulation(scene)
    nv = scene.model.nv
    dt = scene.options.dt
    dofs = [d[1] for d in drives]
    specs = [next(s for s in scene.drives if s.joint == d[0]) for d in drives]
    squares = np.zeros((len(rows), len(drives)))
    alive = np.ones(len(rows), dtype=bool)
    position = np.zeros(nv)
    velocity = np.zeros(nv)
    for k in range(scene.steps):
        fd.apply_targets(scene, reference, k)
        for d in range(nv):
            target = reference.drive(d)
            position[d], velocity[d] = target.target_position, target.target_velocity
        batch.set_drive_targets(position, velocity)
        try:
            batch.step()
        except fd.DivergenceError:
            for i in np.flatnonzero(alive):
                if batch.sim(int(i)).step_count != k + 1:
                    alive[i] = False
        t = (k + 1) * dt
        target_q = np.array([s.target_at(t)[0] for s in specs])
        # Each drive's position as the CSV has it (a spherical axis: PhysX's, not a q entry).
        error = target_q - fd.dof_positions(scene.model, batch.q, dofs)
        squares += error * error
    rms = np.sqrt(squares / max(scene.steps, 1))
    rms[~alive] = np.nan
    return rms, ~alive


def sweep(scene, grid, joint=None, client=None, num_threads=0, chunk_size=None):
    """Runs the scene at every point of the grid; returns a SweepResult.

    scene: a scene file path; grid: the grid text (module docstring) or {name: values};
    joint: only this drive's gains change and its error is the objective (default: every
    implicit drive's gains, objective the total); client: a distributed.Client (default: one
    Batch here); num_threads: the Batch's threads (0: all cores); chunk_size: grid points per
    task on the cluster (default: the grid shared evenly among the workers)."""
    import featherdrive as fd
    from featherdrive_distributed import map_ordered
    if not isinstance(scene, (str, os.PathLike)):
        raise TypeError(f"scene must be a path, not {type(scene).__name__}")
    path = str(scene)
    try:
        text = pathlib.Path(path).read_text()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the scene: {exc.strerror}") from None
    axes = parse_grid(grid)
    parsed = fd.parse_scene(text, path)  # InputError (a ValueError) for a bad scene
    drives, _ = _drives(parsed, joint)
    if isinstance(num_threads, bool) or not isinstance(num_threads, int) or num_threads < 0:
        raise ValueError(f"num_threads = {num_threads!r} must be an integer >= 0")
    points = _points(axes)
    names = [a[0] for a in axes]
    if client is None:
        chunks = [points]
    else:
        if chunk_size is None:
            workers = max(1, len(client.scheduler_info().get("workers", {})))
            chunk_size = -(-len(points) // workers)
        if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
            raise ValueError(f"chunk_size = {chunk_size!r} must be an integer >= 1")
        chunks = [points[i:i + chunk_size] for i in range(0, len(points), chunk_size)]
    items = [(path, text, names, rows, joint, num_threads) for rows in chunks]
    results = map_ordered(evaluate, items, client)
    rms = np.concatenate([r[0] for r in results])
    diverged = np.concatenate([r[1] for r in results])
    return SweepResult(axes, [d[0] for d in drives], joint, rms, diverged)


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        sys.stderr.write(f"featherdrive sweep: {message} (see featherdrive sweep --help)\n")
        sys.exit(2)


def main(argv=None):
    parser = _Parser(
        prog="featherdrive sweep",
        description="Tracking error (RMS of target - q over the run) of a scene's drives over a "
                    "grid of gains: a CSV of the grid and a plot (heat map for two parameters).",
        epilog="Grid: NAME=VALUE, NAME=LO:HI:N (linear) or NAME=LO:HI:N:log (geometric), "
               "comma-separated, NAME stiffness or damping; e.g. "
               "stiffness=10:1000:8:log,damping=1:100:8:log")
    parser.add_argument("scene", help="scene file (YAML or JSON)")
    parser.add_argument("--grid", required=True, help="the grid (see below)")
    parser.add_argument("--joint", help="change only this drive's gains; its error is plotted")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on the Dask cluster of this scheduler (tcp://host:8786)")
    parser.add_argument("--out", metavar="DIR",
                        help="folder for sweep.csv and sweep.png (default: sweep-<scene name>)")
    parser.add_argument("--threads", type=int, default=0,
                        help="threads of each Batch (0: all cores; the default)")
    args = parser.parse_args(argv)
    client = None
    try:
        out = pathlib.Path(args.out or f"sweep-{pathlib.Path(args.scene).stem}")
        if out.exists() and not out.is_dir():
            raise ValueError(f"--out {out}: exists and is not a folder")
        axes = parse_grid(args.grid)
        if len(axes) > 2:
            raise ValueError(f"--grid: {len(axes)} parameters; a sweep plots one or two")
        if args.scheduler:
            from featherdrive_distributed import connect
            client = connect(args.scheduler)
        result = sweep(args.scene, args.grid, joint=args.joint, client=client,
                       num_threads=args.threads)
        out.mkdir(parents=True, exist_ok=True)
        result.write_csv(out / "sweep.csv")
        best = result.best()
        result.plot(out / "sweep.png", f"{pathlib.Path(args.scene).name}: "
                    + " x ".join(f"{n} ({len(a)})" for n, a in zip(result.names, result.axes)))
    except ValueError as exc:
        sys.stderr.write(f"featherdrive sweep: {_one_line(exc)}\n")
        return 2
    except Exception as exc:  # noqa: BLE001 (a run failing: one line, exit 1)
        sys.stderr.write(f"featherdrive sweep: {_one_line(exc)}\n")
        return 1
    finally:
        if client is not None:
            client.close()
    where = f" on {args.scheduler}" if args.scheduler else ""
    print(f"{args.scene}: {len(result.points)} grid points{where}, {len(result.joints)} drives")
    point = ", ".join(f"{n} {v:.6g}" for n, v in zip(result.names, result.points[best]))
    label = f"rms error of {result.joint}" if result.joint else "total rms error"
    print(f"  least {label}: {result.objective[best]:.4e} at {point}")
    if result.diverged.any():
        print(f"  {int(result.diverged.sum())} grid points diverged (nan in the CSV, "
              "diverged = 1)")
    print(f"  grid: {out / 'sweep.csv'}")
    print(f"  plot: {out / 'sweep.png'}")
    return 0


def _one_line(exc):
    return " ".join(str(exc).split("\n"))


if __name__ == "__main__":
    sys.exit(main())
