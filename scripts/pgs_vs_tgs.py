#!/usr/bin/python3
"""PGS against TGS: the pictures and tables of docs/math/pgs_vs_tgs.md.

Reads the CSV files written by the example program `pgs_vs_tgs` (examples/pgs_vs_tgs.cpp),
integrates the continuous PD laws finely with a classical RK4 (numpy only), writes
docs/math/pgs_vs_tgs_step.png and docs/math/pgs_vs_tgs_sine.png and prints the error tables.

    build/examples/pgs_vs_tgs /tmp/pgs_vs_tgs
    /usr/bin/python3 scripts/pgs_vs_tgs.py /tmp/pgs_vs_tgs [OUTPUT_DIR]

OUTPUT_DIR defaults to docs/math next to this script's repository root.
"""

import math
import os
import sys

import numpy as np

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

FINE = 400  # RK4 steps per simulation step for the continuous references


# ---------------------------------------------------------------------------------------------
# Input


def read_csv(path):
    """Returns (params, columns): the '# key=value' line as floats and the named columns."""
    with open(path) as f:
        first = f.readline()
    params = {}
    for token in first.lstrip("#").split():
        if "=" in token:
            key, value = token.split("=", 1)
            try:
                params[key] = float(value)
            except ValueError:
                params[key] = value
    data = np.genfromtxt(path, delimiter=",", names=True, skip_header=1)
    return params, data


# ---------------------------------------------------------------------------------------------
# Continuous references


def rk4_steps(f, y0, t_grid, fine):
    """Integrates y' = f(t, y, k) over each interval [t_k, t_{k+1}] of t_grid with `fine` RK4 steps,
    k the interval's index (so right-hand sides may change between intervals); returns y at t_grid."""
    y = np.array(y0, dtype=float)
    out = np.empty((len(t_grid), len(y)))
    out[0] = y
    for k in range(len(t_grid) - 1):
        t0, t1 = t_grid[k], t_grid[k + 1]
        h = (t1 - t0) / fine
        for s in range(fine):
            t = t0 + s * h
            k1 = f(t, y, k)
            k2 = f(t + 0.5 * h, y + 0.5 * h * k1, k)
            k3 = f(t + 0.5 * h, y + 0.5 * h * k2, k)
            k4 = f(t + h, y + h * k3, k)
            y = y + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        out[k + 1] = y
    return out


def slider_pd(m, kp, kd, target, t_grid, fine=FINE):
    """m x'' = kp (xT(t) - x) + kd (vT(t) - x'), x(0) = x'(0) = 0. target(t, k) -> (xT, vT).
    The same RK4 as rk4_steps, written on scalars (this one runs millions of times)."""

    def acc(t, x, v, k):
        xt, vt = target(t, k)
        return (kp * (xt - x) + kd * (vt - v)) / m

    x = v = 0.0
    out = np.empty((len(t_grid), 2))
    out[0] = (x, v)
    for k in range(len(t_grid) - 1):
        t0 = t_grid[k]
        h = (t_grid[k + 1] - t0) / fine
        for s in range(fine):
            t = t0 + s * h
            a1 = acc(t, x, v, k)
            a2 = acc(t + 0.5 * h, x + 0.5 * h * v, v + 0.5 * h * a1, k)
            v2 = v + 0.5 * h * a1
            a3 = acc(t + 0.5 * h, x + 0.5 * h * v2, v + 0.5 * h * a2, k)
            v3 = v + 0.5 * h * a2
            a4 = acc(t + h, x + h * v3, v + h * a3, k)
            v4 = v + h * a3
            x, v = x + h / 6.0 * (v + 2 * v2 + 2 * v3 + v4), v + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
        out[k + 1] = (x, v)
    return out


class PlanarChain:
    """The example's chain in closed form: revolute joints about y, rods of mass m and length l
    hanging along -z, centre of mass at mid-length, I_yy = m l^2 / 12, gravity g along -z.
    The absolute angle of link i is phi_i = q_1 + ... + q_i; its direction (x, z) is
    d_i = (-sin phi_i, -cos phi_i), since a rotation by phi about +y takes -z there."""

    def __init__(self, n, m, l, g):
        self.n, self.m, self.l, self.g = n, m, l, g
        self.I = m * l * l / 12.0
        # w[i, k]: lever of link k's direction in link i's centre of mass.
        self.w = np.zeros((n, n))
        for i in range(n):
            self.w[i, :i] = l
            self.w[i, i] = l / 2
        self.lower = np.tril(np.ones((n, n)))  # phi = lower @ q

    def dynamics(self, q, qd):
        """M(q) and bias(q, qd) = c(q, qd) - g(q), the joint forces that hold zero acceleration."""
        n, m = self.n, self.m
        phi = self.lower @ q
        phid = self.lower @ qd
        d = np.stack([-np.sin(phi), -np.cos(phi)], axis=1)   # (n, 2)
        dp = np.stack([-np.cos(phi), np.sin(phi)], axis=1)   # d d / d phi
        M = self.I * self.lower.T @ self.lower
        bias = np.zeros(n)
        for i in range(n):
            # d c_i / d phi_k = w[i, k] dp_k, d phi_k / d q_j = [j <= k].
            Jphi = self.w[i][:, None] * dp                   # (n links k, 2)
            J = (self.lower.T @ Jphi).T                      # (2, n joints j)
            M += m * J.T @ J
            acc_bias = -(self.w[i][:, None] * d * (phid ** 2)[:, None]).sum(axis=0)
            bias += m * J.T @ acc_bias
            bias += m * self.g * J[1]                        # dV/dq, V = m g z
        return M, bias

    def pd(self, kp, kd, xT, t_grid, fine=FINE):
        n = self.n

        def f(t, y, k):
            q, qd = y[:n], y[n:]
            M, bias = self.dynamics(q, qd)
            tau = kp * (xT - q) - kd * qd - bias
            return np.concatenate([qd, np.linalg.solve(M, tau)])

        return rk4_steps(f, np.zeros(2 * n), t_grid, fine)


def check_chain_model(path):
    p, data = read_csv(path)
    chain = PlanarChain(int(p["links"]), p["m"], p["l"], p["g"])
    n = chain.n
    worst = 0.0
    for row in np.atleast_1d(data):
        q = np.array([row["q%d" % (j + 1)] for j in range(n)])
        qd = np.array([row["qd%d" % (j + 1)] for j in range(n)])
        M_fd = np.array([[row["M%d%d" % (r + 1, c + 1)] for c in range(n)] for r in range(n)])
        b_fd = np.array([row["bias%d" % (j + 1)] for j in range(n)])
        M, b = chain.dynamics(q, qd)
        worst = max(worst, np.abs(M - M_fd).max(), np.abs(b - b_fd).max())
    print("chain model check: max |M - M_featherdrive|, |bias - bias_featherdrive| = %.1e" % worst)
    if worst > 1e-9:
        raise SystemExit("the script's chain model does not match featherdrive's CRBA/RNEA")
    return chain


# ---------------------------------------------------------------------------------------------
# Figures


COLORS = {"pgs": "tab:blue", "tgs": "tab:orange", "tgs_many": "tab:green", "pl": "tab:red"}


def step_figure(indir, outdir):
    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
    # (a), (b): the slider, soft and stiff.
    for ax, name, title in ((axes[0, 0], "slider_step_soft", "soft"),
                            (axes[0, 1], "slider_step_stiff", "stiff")):
        p, d = read_csv(os.path.join(indir, name + ".csv"))
        m, kp, kd, xT = p["m"], p["kp"], p["kd"], p["xT"]
        t = d["t"]
        fine_t = np.linspace(0.0, t[-1], 20 * (len(t) - 1) + 1)
        ref = slider_pd(m, kp, kd, lambda tt, k: (xT, 0.0), fine_t, fine=40)
        wn = np.sqrt(kp / m)
        zeta = kd / (2 * np.sqrt(kp * m))
        ax.axhline(xT, color="0.6", ls="--", lw=1, label="target $x_T$")
        ax.plot(fine_t, ref[:, 0], color="k", lw=1.2, label="continuous PD")
        ax.plot(t, d["pgs4_1_x"], "o-", ms=3, lw=0.8, color=COLORS["pgs"], label="PGS 4/1")
        ax.plot(t, d["tgs4_1_x"], "s-", ms=3, lw=0.8, color=COLORS["tgs"], label="TGS 4/1")
        ax.set_title("(%s) 1 kg slider, %s drive: $k_p$ = %g N/m, $k_d$ = %g Ns/m\n"
                     "($\\omega_n$ = %g rad/s, $\\zeta$ = %.2g, $\\omega_n \\tau$ = %.2g)"
                     % ("a" if title == "soft" else "b", title, kp, kd, wn, zeta, wn * p["dt"]),
                     fontsize=10)
        ax.set_xlabel("time t [s]")
        ax.set_ylabel("slider position x [m]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")

    # (c), (d): the chain under gravity.
    p, d = read_csv(os.path.join(indir, "chain_step.csv"))
    chain = check_chain_model(os.path.join(indir, "chain_dynamics_check.csv"))
    n = chain.n
    xT = np.array([p["xT%d" % (j + 1)] for j in range(n)])
    t = d["t"]
    fine_t = np.linspace(0.0, t[-1], 4 * (len(t) - 1) + 1)
    ref_fine = chain.pd(p["kp"], p["kd"], xT, fine_t, fine=FINE // 4)
    ref = ref_fine[::4]
    ax = axes[1, 0]
    joint_colors = ["tab:purple", "tab:brown", "tab:cyan"]
    for j in range(n):
        c = joint_colors[j % len(joint_colors)]
        ax.plot(fine_t, ref_fine[:, j], color=c, lw=1.2)
        ax.plot(t, d["pgs4_1_q%d" % (j + 1)], "o", ms=2.5, color=c, mfc="none")
        ax.plot(t, d["tgs4_1_q%d" % (j + 1)], "x", ms=3, color=c)
        ax.axhline(xT[j], color=c, ls=":", lw=0.8)
    handles = [Line2D([], [], color=joint_colors[j], lw=2, label="joint %d" % (j + 1)) for j in range(n)]
    handles += [Line2D([], [], color="k", lw=1.2, label="continuous PD"),
                Line2D([], [], color="k", marker="o", mfc="none", ls="none", ms=4, label="PGS 4/1"),
                Line2D([], [], color="k", marker="x", ls="none", ms=4, label="TGS 4/1"),
                Line2D([], [], color="k", ls=":", lw=0.8, label="targets")]
    ax.legend(handles=handles, fontsize=8, ncol=4, loc="upper center")
    ax.set_ylim(-0.8, 1.35)
    ax.set_title("(c) 3-link chain under gravity, %g kg / %g m rods, $k_p$ = %g Nm/rad, "
                 "$k_d$ = %g Nms/rad" % (p["m"], p["l"], p["kp"], p["kd"]), fontsize=10)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("joint angle q [rad]")
    ax.grid(alpha=0.3)
    ax.set_xlim(0, 1.5)

    ax = axes[1, 1]
    for label, key in (("PGS 4/1", "pgs4_1"), ("TGS 4/1", "tgs4_1")):
        q = np.stack([d["%s_q%d" % (key, j + 1)] for j in range(n)], axis=1)
        err = np.abs(q - ref[:, :n]).max(axis=1)
        ax.semilogy(t[1:], err[1:], color=COLORS[key[:3]], label=label)
    ax.set_title("(d) chain: distance from the continuous PD response", fontsize=10)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("max over joints |q - q_continuous| [rad]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.suptitle("Step response, PGS and TGS at 4 position / 1 velocity iterations, "
                 "$\\tau$ = 1/60 s", fontsize=12)
    fig.tight_layout()
    path = os.path.join(outdir, "pgs_vs_tgs_step.png")
    fig.savefig(path, dpi=110)
    print("wrote", path)

    # Numbers for the doc.
    print("\nStep responses: max |x - x_continuous| over the run")
    for name in ("slider_step_soft", "slider_step_stiff"):
        p2, d2 = read_csv(os.path.join(indir, name + ".csv"))
        ref2 = slider_pd(p2["m"], p2["kp"], p2["kd"], lambda tt, k: (p2["xT"], 0.0), d2["t"])
        print("  %-18s PGS 4/1 %.2e m   TGS 4/1 %.2e m" % (
            name, np.abs(d2["pgs4_1_x"] - ref2[:, 0]).max(), np.abs(d2["tgs4_1_x"] - ref2[:, 0]).max()))
    for label, key in (("PGS 4/1", "pgs4_1"), ("TGS 4/1", "tgs4_1")):
        q = np.stack([d["%s_q%d" % (key, j + 1)] for j in range(n)], axis=1)
        err = np.abs(q - ref[:, :n])
        late = t >= 2.0
        print("  chain %-8s max |q - q_cont| %.2e rad (whole run), %.2e rad (t >= 2 s); "
              "q(3 s) - q_cont(3 s) = %s" % (label, err.max(), err[late].max(),
                                             np.array2string(q[-1] - ref[-1, :n], precision=2)))
    plt.close(fig)


def sine_references(p, t):
    """Continuous PD (continuous target), PD with TGS's piecewise-linear target (position target
    interpolated back from the step-end sample, velocity target held at the step-end sample), and
    PD with the interpolated position but the continuous velocity target."""
    m, kp, kd, A = p["m"], p["kp"], p["kd"], p["amplitude"]
    w = 2 * np.pi * p["hz"]
    dt = t[1] - t[0]

    def continuous(tt, k):
        return A * math.sin(w * tt), A * w * math.cos(w * tt)

    def piecewise(tt, k):
        t_end = t[k + 1]
        xe, ve = A * math.sin(w * t_end), A * w * math.cos(w * t_end)
        return xe - (t_end - tt) * ve, ve

    def piecewise_position_only(tt, k):
        return piecewise(tt, k)[0], A * w * math.cos(w * tt)

    return (slider_pd(m, kp, kd, continuous, t), slider_pd(m, kp, kd, piecewise, t),
            slider_pd(m, kp, kd, piecewise_position_only, t), dt)


def sine_figure(indir, outdir):
    settings = [("PGS 4/1", "pgs4_1"), ("PGS 64/1", "pgs64_1"), ("TGS 4/1", "tgs4_1"),
                ("TGS 16/1", "tgs16_1"), ("TGS 64/1", "tgs64_1"), ("TGS 1024/1", "tgs1024_1")]
    freqs = (0.5, 1.0, 2.0, 4.0)
    table = {}
    refs = {}
    for hz in freqs:
        p, d = read_csv(os.path.join(indir, "slider_sine_%gHz.csv" % hz))
        t = d["t"]
        cont, pl, pl_pos, dt = sine_references(p, t)
        refs[hz] = (p, d, cont, pl)
        late = t >= 1.0  # the start-up transient has decayed (zeta = 1, omega_n = 10 rad/s)
        row = {}
        row["lag"] = np.abs(cont[late, 0] - d["target_x"][late]).max()
        for label, key in settings:
            row[key] = (np.abs(d[key + "_x"][late] - cont[late, 0]).max(),
                        np.abs(d[key + "_v"][late] - cont[late, 1]).max(),
                        np.abs(d[key + "_x"][late] - pl[late, 0]).max())
        row["pl"] = (np.abs(pl[late, 0] - cont[late, 0]).max(), np.abs(pl[late, 1] - cont[late, 1]).max())
        row["pl_pos"] = np.abs(pl_pos[late, 0] - cont[late, 0]).max()
        # First-order estimate of the piecewise-linear target's effect (doc, "moving target").
        m, kp, kd, A = p["m"], p["kp"], p["kd"], p["amplitude"]
        w = 2 * np.pi * hz
        force = abs(kp * (w * dt) ** 2 / 6 - kd * w * w * dt / 2) * A
        row["estimate"] = force / abs(kp - m * w * w + 1j * kd * w)
        table[hz] = row

    p, d, cont, pl = refs[1.0]
    t = d["t"]
    fig, axes = plt.subplots(3, 1, figsize=(11, 12))
    ax = axes[0]
    fine_t = np.linspace(0, 3, 3001)
    A, w = p["amplitude"], 2 * np.pi * p["hz"]
    ax.plot(fine_t, A * np.sin(w * fine_t), color="0.6", ls="--", lw=1, label="target $x_T(t)$")
    ref_fine = slider_pd(p["m"], p["kp"], p["kd"],
                         lambda tt, k: (A * np.sin(w * tt), A * w * np.cos(w * tt)),
                         np.linspace(0, 3, 601), fine=20)
    ax.plot(np.linspace(0, 3, 601), ref_fine[:, 0], color="k", lw=1.2, label="continuous PD")
    sel = t <= 3.0
    ax.plot(t[sel], d["pgs4_1_x"][sel], "o", ms=3, color=COLORS["pgs"], label="PGS 4/1")
    ax.plot(t[sel], d["tgs4_1_x"][sel], "s", ms=3, mfc="none", color=COLORS["tgs"], label="TGS 4/1")
    ax.set_title("(a) 1 kg slider tracking a 1 Hz sine of amplitude %g m, target sampled at the end "
                 "of each step; $k_p$ = %g N/m, $k_d$ = %g Ns/m ($\\zeta$ = 1)"
                 % (A, p["kp"], p["kd"]), fontsize=10)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("slider position x [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=4, loc="lower left")

    ax = axes[1]
    sel = (t >= 2.0) & (t <= 4.0)
    ax.plot(t[sel], (d["pgs4_1_x"] - cont[:, 0])[sel] * 1e3, "o-", ms=2.5, lw=0.8, color=COLORS["pgs"],
            label="PGS 4/1")
    ax.plot(t[sel], (d["tgs4_1_x"] - cont[:, 0])[sel] * 1e3, "s-", ms=2.5, lw=0.8, color=COLORS["tgs"],
            label="TGS 4/1")
    ax.plot(t[sel], (d["tgs1024_1_x"] - cont[:, 0])[sel] * 1e3, "^", ms=3.5, color=COLORS["tgs_many"],
            label="TGS 1024/1")
    ax.plot(t[sel], (pl[:, 0] - cont[:, 0])[sel] * 1e3, color=COLORS["pl"], lw=1.2,
            label="continuous PD with TGS's piecewise-linear target")
    ax.axhline(0, color="k", lw=0.8)
    lim = 1.6 * np.abs((d["pgs4_1_x"] - cont[:, 0])[sel]).max() * 1e3
    ax.set_ylim(-lim, lim)
    ax.set_title("(b) 1 Hz: position minus the continuous PD response (steady state)", fontsize=10)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("x - x_continuous [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=4, loc="upper center")

    ax = axes[2]
    fr = np.array(freqs)
    styles = {"pgs4_1": dict(color=COLORS["pgs"], marker="o", ms=9, mfc="none"),
              "pgs64_1": dict(color=COLORS["pgs"], marker="+", ms=9, ls="--"),
              "tgs4_1": dict(color=COLORS["tgs"], marker="s"),
              "tgs16_1": dict(color="tab:olive", marker="v"),
              "tgs64_1": dict(color="tab:cyan", marker="^"),
              "tgs1024_1": dict(color=COLORS["tgs_many"], marker="D", ms=4)}
    for label, key in settings:
        ax.loglog(fr, [table[h][key][0] * 1e3 for h in freqs], label=label, lw=1, **styles[key])
    ax.loglog(fr, [table[h]["pl"][0] * 1e3 for h in freqs], "k--", lw=1.5,
              label="PD with piecewise-linear target (TGS limit)")
    ax.loglog(fr, [table[h]["lag"] * 1e3 for h in freqs], ":", color="0.5", lw=1.5,
              label="PD law's own tracking error |x_cont - x_T|")
    ax.set_title("(c) steady-state error amplitude against the continuous PD response, by target "
                 "frequency ($\\tau$ = 1/60 s)", fontsize=10)
    ax.set_xlabel("target frequency [Hz]")
    ax.set_xticks(fr)
    ax.set_xticks([], minor=True)
    ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    ax.set_ylabel("max |x - x_continuous| [mm]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    path = os.path.join(outdir, "pgs_vs_tgs_sine.png")
    fig.savefig(path, dpi=110)
    print("wrote", path)
    plt.close(fig)

    print("\nSine tracking, amplitude %g m, kp = %g N/m, kd = %g Ns/m, tau = 1/60 s; errors over "
          "1 s <= t <= 6 s" % (A, p["kp"], p["kd"]))
    print("max |x - x_cont| [mm]:")
    header = "  %-40s" % "" + "".join("%10g Hz" % h for h in freqs)
    print(header)
    print("  %-40s" % "PD law's own error |x_cont - x_T|" + "".join("%13.4f" % (table[h]["lag"] * 1e3) for h in freqs))
    for label, key in settings:
        print("  %-40s" % label + "".join("%13.4f" % (table[h][key][0] * 1e3) for h in freqs))
    print("  %-40s" % "PD, piecewise-linear target" + "".join("%13.4f" % (table[h]["pl"][0] * 1e3) for h in freqs))
    print("  %-40s" % "  ... its position part only" + "".join("%13.4f" % (table[h]["pl_pos"] * 1e3) for h in freqs))
    print("  %-40s" % "  ... first-order estimate" + "".join("%13.4f" % (table[h]["estimate"] * 1e3) for h in freqs))
    print("max |v - v_cont| [mm/s]:")
    for label, key in settings:
        print("  %-40s" % label + "".join("%13.4f" % (table[h][key][1] * 1e3) for h in freqs))
    print("  %-40s" % "PD, piecewise-linear target" + "".join("%13.4f" % (table[h]["pl"][1] * 1e3) for h in freqs))
    print("max |x - x_piecewise-linear-target PD| [mm]:")
    for label, key in settings:
        if key.startswith("tgs"):
            print("  %-40s" % label + "".join("%13.5f" % (table[h][key][2] * 1e3) for h in freqs))


def secant_table(indir):
    """The same sine with the secant velocity target (x_T(t_k+1) - x_T(t_k)) / tau: TGS's
    interpolated target is then the polyline through the samples."""
    freqs = (0.5, 1.0, 2.0, 4.0)
    rows = {}
    for hz in freqs:
        p, d = read_csv(os.path.join(indir, "slider_sine_secant_%gHz.csv" % hz))
        t = d["t"]
        m, kp, kd, A = p["m"], p["kp"], p["kd"], p["amplitude"]
        w = 2 * np.pi * hz

        def continuous(tt, k):
            return A * math.sin(w * tt), A * w * math.cos(w * tt)

        def polyline(tt, k):
            t0, t1 = t[k], t[k + 1]
            x0, x1 = A * math.sin(w * t0), A * math.sin(w * t1)
            slope = (x1 - x0) / (t1 - t0)
            return x1 - (t1 - tt) * slope, slope

        cont = slider_pd(m, kp, kd, continuous, t)
        poly = slider_pd(m, kp, kd, polyline, t)
        late = t >= 1.0
        rows[hz] = {key: np.abs(d[key + "_x"][late] - cont[late, 0]).max()
                    for key in ("pgs4_1", "tgs4_1", "tgs1024_1")}
        rows[hz]["poly"] = np.abs(poly[late, 0] - cont[late, 0]).max()
        rows[hz]["tgs_vs_poly"] = np.abs(d["tgs1024_1_x"][late] - poly[late, 0]).max()
    print("\nSame sine, velocity target = secant of the samples; max |x - x_cont| [mm]:")
    print("  %-40s" % "" + "".join("%10g Hz" % h for h in freqs))
    for label, key in (("PGS 4/1", "pgs4_1"), ("TGS 4/1", "tgs4_1"), ("TGS 1024/1", "tgs1024_1"),
                       ("PD, polyline target (TGS limit)", "poly"),
                       ("TGS 1024/1 vs PD with polyline target", "tgs_vs_poly")):
        print("  %-40s" % label + "".join("%13.4f" % (rows[h][key] * 1e3) for h in freqs))


def rest_tables(indir):
    p, d = read_csv(os.path.join(indir, "slider_rest.csv"))
    print("\nAt rest under gravity: 1 kg slider, kp = %g N/m, kd = %g Ns/m, target 0 "
          "(static sag -m g / kp = %.6f m), after %d steps" % (p["kp"], p["kd"], -p["m"] * p["g"] / p["kp"], p["steps"]))
    print("  %-10s %12s %14s %12s %14s" % ("solver", "x [m]", "v [m/s]", "force [N]", "x change/step"))
    for row in np.atleast_1d(d):
        name = "%s %d/%d" % ("PGS" if row["solver"] == 0 else "TGS", row["position_iterations"],
                             row["velocity_iterations"])
        print("  %-10s %12.6f %14.6f %12.6f %14.1e" % (name, row["x"], row["v"], row["force"], row["x_change_last_step"]))
    p, d = read_csv(os.path.join(indir, "chain_step_rest.csv"))
    print("\nThe chain of the step figure (kp = %g, kd = %g) at rest after %d steps: q - static sag "
          "[rad], qd [rad/s], F - g(q) - c(q, qd) [Nm]" % (p["kp"], p["kd"], p["steps"]))
    for row in np.atleast_1d(d):
        name = "%s %d/%d" % ("PGS" if row["solver"] == 0 else "TGS", row["position_iterations"],
                             row["velocity_iterations"])
        vals = lambda key: " ".join("%10.2e" % row["%s%d" % (key, j + 1)] for j in range(3))
        print("  %-9s q-sag %s | qd %s | F-g-c %s | q change/step %.0e" % (
            name, vals("q_minus_sag"), vals("qd"), vals("force_minus_gravity_minus_c"),
            row["max_abs_q_change_last_step"]))
    p, d = read_csv(os.path.join(indir, "chain_rest.csv"))
    print("\nChain at rest under gravity, critically damped drives, after %d steps" % p["steps"])
    print("  %-11s %8s %16s %12s %16s" % ("solver", "kp", "|q - sag| [rad]", "|qd| [rad/s]", "|F - g(q)| [Nm]"))
    for row in np.atleast_1d(d):
        name = "%s %d/%d" % ("PGS" if row["solver"] == 0 else "TGS", row["position_iterations"],
                             row["velocity_iterations"])
        print("  %-11s %8.0e %16.2e %12.2e %16.2e" % (name, row["kp"], row["max_abs_q_minus_static_sag"],
                                                   row["max_abs_qd"], row["max_abs_force_minus_gravity"]))


def main():
    if len(sys.argv) not in (2, 3):
        raise SystemExit(__doc__)
    indir = sys.argv[1]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    outdir = sys.argv[2] if len(sys.argv) == 3 else os.path.join(root, "docs", "math")
    os.makedirs(outdir, exist_ok=True)
    step_figure(indir, outdir)
    sine_figure(indir, outdir)
    secant_table(indir)
    rest_tables(indir)


if __name__ == "__main__":
    main()
