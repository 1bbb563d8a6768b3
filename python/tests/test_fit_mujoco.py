"""Model mismatch: a log made by MuJoCo 2.2.2 (fd.run_mujoco, the bridge) with the *literal*
mapping (PhysX's kp and kd as MuJoCo's explicit actuators: another drive law), fitted with
featherdrive's (PhysX's implicit) drive. The fit converges, its residual is the replay's and far
above a same-law fit's, its intervals are finite, and it recovers the gains the bridge's inverse
translation (fd.translate_to_physx) predicts, not the literal ones (docs/fitting.md)."""
import numpy as np
import pytest

import featherdrive as fd
import featherdrive_fit
from conftest import ARM, ROOT
from test_fit import DT, ROWS, chirp_targets, replay, write, write_log

# Every joint's drive law differs, so every joint's gains are unknowns (from 2x off), and the
# armature of joint2 and joint4 with them (ARMATURE) or not.
GAINS = "fit:\n  parameters:\n" + "".join(
    f"    - {{quantity: stiffness, joints: [joint{i}], bounds: [10, 5000], "
    f"initial: {1200 if i == 2 else 600 if i == 4 else 200}}}\n"
    f"    - {{quantity: damping, joints: [joint{i}], bounds: [0.1, 100], "
    f"initial: {6 if i == 2 else 3 if i == 4 else 1}}}\n" for i in range(1, 8))
ARMATURE = ("    - {quantity: armature, joints: [joint2], bounds: [0.001, 1], initial: 0.04}\n"
            "    - {quantity: armature, joints: [joint4], bounds: [0.001, 1], initial: 0.08}\n")


def scene_text(fit="", stiffness2=600, damping2=12, stiffness4=300, damping4=6):
    """test_fit's gains and armature on what MuJoCo gets too: no gravity (the translation is
    exact without a load), no joint friction, no velocity limits; armature on every joint keeps
    MuJoCo's explicit copy of the light wrist joints stable (kp dt^2 / m <= 0.04)."""
    joints = ", ".join(f"joint{i}: {{armature: {0.08 if i == 2 else 0.04 if i == 4 else 0.05}, "
                       "max_velocity: 1000, friction: {static: 0, dynamic: 0, viscous: 0}}"
                       for i in range(1, 8))
    return (f"model: {ARM}\nsteps: {ROWS - 1}\ndt: {DT!r}\ngravity: [0, 0, 0]\n"
            "solver: {type: pgs, position_iterations: 4, velocity_iterations: 1}\n"
            "drive_defaults: {type: force, stiffness: 100, damping: 2}\n"
            f"drives: {{joint2: {{stiffness: {stiffness2!r}, damping: {damping2!r}}},\n"
            f"         joint4: {{stiffness: {stiffness4!r}, damping: {damping4!r}}}}}\n"
            f"joints: {{{joints}}}\n" + fit)


def mujoco_log(tmp_path, scene, drives):
    sim = fd.make_simulation(scene)
    targets = chirp_targets(scene.model.nv)
    q, qd = fd.run_mujoco(sim, ROWS - 1, targets[:-1], drives=drives)
    assert q.shape == (ROWS, scene.model.nv) and np.abs(q).max() > 0.1  # MuJoCo moved the arm
    write_log(tmp_path / f"{drives}.csv", scene.model.dof_names, q, qd, targets)
    return q


def test_run_mujoco_translated_replays_featherdrive(tmp_path):
    """The bridge's claim through the binding (an independent engine): MuJoCo with translated
    drives replays featherdrive's run; the literal copy does not. sim is left untouched."""
    scene = fd.parse_scene(scene_text(), str(tmp_path / "s.yaml"))
    sim = fd.make_simulation(scene)
    targets = chirp_targets(scene.model.nv)
    ours, _ = replay(scene, targets)
    translated, _ = fd.run_mujoco(sim, ROWS - 1, targets[:-1])
    literal, _ = fd.run_mujoco(sim, ROWS - 1, targets[:-1], "literal", "euler")
    assert sim.step_count == 0 and np.abs(sim.q).max() == 0
    print(np.abs(translated - ours).max(), np.abs(literal - ours).max())
    assert np.abs(translated - ours).max() < 1e-3 * np.abs(ours).max()
    assert np.abs(literal - ours).max() > 0.05 * np.abs(ours).max()


def fit(tmp_path, text, log):
    write(tmp_path / "fit.yaml", text)
    result = fd.fit(str(tmp_path / "fit.yaml"), str(log), threads=1)
    print(result.table())
    return result


def translated(scene, inertia):
    """translate_to_physx of each joint's literal MuJoCo setting (eq. B11-B12) on the inertia
    inertia(sim, dof): the bridge's closed form, which the fit never sees."""
    sim = fd.make_simulation(scene)
    out = {}
    for d in fd.export_mjcf(sim, drives="literal")["drives"]:
        dof = scene.model.dof_names.index(d["joint"])
        out[d["joint"]] = fd.translate_to_physx(inertia(sim, dof), d["mujoco"], sim.options)
    return out


def test_fit_of_a_mujoco_literal_log(tmp_path):
    scene = fd.parse_scene(scene_text(), str(tmp_path / "truth.yaml"))
    logged = mujoco_log(tmp_path, scene, "literal")
    result = fit(tmp_path, scene_text(GAINS + ARMATURE), tmp_path / "literal.csv")
    assert result.converged, result.table()
    # The reported residual is the fitted scene's replay against the log.
    text = featherdrive_fit.fitted_scene_text(result, fd.load_scene(str(tmp_path / "fit.yaml")))
    fitted = fd.parse_scene(text, str(tmp_path / "fitted.yaml"))
    q, qd = replay(fitted, chirp_targets(fitted.model.nv))
    assert result.rms == pytest.approx(np.sqrt(np.mean((q - logged) ** 2)), rel=1e-9)
    for e in result.estimates:
        assert np.isfinite(e.ci95) and e.ci95 > 0, result.table()
    # A same-law log (featherdrive's own, from the fitted values) is fitted to round-off: the
    # literal log's residual is the mismatch of the drive laws.
    write_log(tmp_path / "same.csv", fitted.model.dof_names, q, qd, chirp_targets(7))
    same = fit(tmp_path, scene_text(GAINS + ARMATURE), tmp_path / "same.csv")
    print("rms", result.rms, "same law", same.rms)
    assert same.rms < 1e-9 and result.rms > 1e3 * same.rms
    # The armature held at the scene's (as the translation holds it): the fitted gains are the
    # inverse translation's on the inertia each joint has with the others held (M_jj: every
    # joint is driven), not on the bridge's 1 / (M^-1)_jj (the others free), nor the literal ones.
    result = fit(tmp_path, scene_text(GAINS), tmp_path / "literal.csv")
    assert result.converged, result.table()
    held = translated(scene, lambda sim, d: sim.mass_matrix()[d, d])
    free = translated(scene, lambda sim, d: fd.effective_inertia(scene.model, sim.q)[d])
    for j in ("joint2", "joint4"):
        kp, kd = result.value("stiffness", j), result.value("damping", j)
        print(j, kp, kd, "held", held[j].drive, "free", free[j].drive)
        assert kp == pytest.approx(held[j].drive.stiffness, rel=0.01)
        assert kd == pytest.approx(held[j].drive.damping, rel=0.06)
        assert abs(kp / free[j].drive.stiffness - 1) > 0.03


def test_fit_of_a_lone_joint_recovers_the_translation(tmp_path):
    """One slider, where the inverse translation is exact: the fit of MuJoCo's literal log
    recovers translate_to_physx's gains to round-off, with a round-off residual."""
    text = (f"model: {ROOT / 'examples' / 'slider.urdf'}\nsteps: {ROWS - 1}\ndt: {DT!r}\n"
            "gravity: [0, 0, 0]\n"
            "solver: {type: pgs, position_iterations: 4, velocity_iterations: 1}\n"
            "drives: {slide: {type: force, stiffness: 2000, damping: 40}}\n"
            "joints: {slide: {max_velocity: 1000}}\n")
    scene = fd.parse_scene(text, str(tmp_path / "slider.yaml"))
    sim = fd.make_simulation(scene)
    targets = 0.1 * chirp_targets(1)
    q, qd = fd.run_mujoco(sim, ROWS - 1, targets[:-1], "literal")
    write_log(tmp_path / "slider.csv", ["slide"], q, qd, targets)
    result = fit(tmp_path, text + "fit:\n  parameters:\n"
                 "    - {quantity: stiffness, joints: [slide], bounds: [100, 1e5], initial: 4000}\n"
                 "    - {quantity: damping, joints: [slide], bounds: [1, 1000], initial: 20}\n",
                 tmp_path / "slider.csv")
    exact = translated(scene, lambda sim, d: fd.effective_inertia(scene.model, sim.q)[d])["slide"]
    print(exact.drive, exact.exact, result.value("stiffness", "slide") / exact.drive.stiffness - 1,
          result.value("damping", "slide") / exact.drive.damping - 1)
    assert exact.exact and result.converged and result.rms < 1e-9
    assert result.value("stiffness", "slide") == pytest.approx(exact.drive.stiffness, rel=1e-9)
    assert result.value("damping", "slide") == pytest.approx(exact.drive.damping, rel=1e-9)
    assert abs(exact.drive.stiffness / 2000 - 1) > 0.01  # not the literal gains


def test_bad_arguments(tmp_path):
    scene = fd.parse_scene(scene_text(), str(tmp_path / "s.yaml"))
    sim = fd.make_simulation(scene)
    targets = np.zeros((10, scene.model.nv))
    with pytest.raises(ValueError, match=r"^drives = 'exact': must be 'translated' or 'literal'$"):
        fd.run_mujoco(sim, 10, targets, drives="exact")
    with pytest.raises(ValueError, match=r"^integrator = 'rk4': must be 'euler' or 'implicit'$"):
        fd.run_mujoco(sim, 10, targets, integrator="rk4")
    with pytest.raises(ValueError, match=r"^run_mujoco: target_position is \(10, 7\), expected "
                                         r"\(9, 7\)$"):
        fd.run_mujoco(sim, 9, targets)
    targets[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"^run_mujoco: target_position\[3, 1\] = nan: must be "
                                         r"finite$"):
        fd.run_mujoco(sim, 10, targets)
    # Literal gains far past MuJoCo's explicit limit (kp dt^2 / m >> 4): divergence, not a log.
    stiff = fd.parse_scene(scene_text(stiffness4=1e7), str(tmp_path / "stiff.yaml"))
    with pytest.raises(RuntimeError, match=r"^run_mujoco: MuJoCo diverged at step \d+ "
                                           r"\(drives literal, dt "):
        fd.run_mujoco(fd.make_simulation(stiff), ROWS - 1, chirp_targets(7)[:-1], "literal")
