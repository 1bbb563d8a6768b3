"""fd.Batch through the SIMD lanes: environments in lanes equal the scalar Batch (lanes off) with
the same per-environment parameters within 1e-12, every width (Batch.isa) gives the same bits, and
bad input raises ValueError. fd.SimdBatch, deprecated, is a Batch that must step in lanes."""
import pathlib

import numpy as np
import pytest

import featherdrive as fd
from conftest import in_lanes

N = 11  # not a multiple of any width


def arm_prototype(fixed_base=True):
    """examples/arm7.urdf as loaded: its URDF velocity limits stay on."""
    options = fd.UrdfOptions(fixed_base=fixed_base)
    model = fd.load_urdf(fd.example_path("arm7.urdf"), options).model
    return fd.Simulation(model, dt=1 / 240, solver="tgs", position_iterations=4,
                         stiffness=2e4, damping=100.0)


def self_colliding():
    """The quadruped on the ground with self-collision on, which the lanes do not step (its rows
    are solved outside the sweep)."""
    root = pathlib.Path(__file__).resolve().parents[2]
    sim = fd.make_simulation(fd.load_scene(root / "tests" / "data" / "quadruped_ground.yaml"))
    sim.set_contact_options(fd.ContactOptions(self_collision=True))
    return sim


def randomise(batch, rng, nv):
    kp = rng.uniform(1e4, 3e4, (N, nv))
    targets = rng.uniform(-0.5, 0.5, (N, nv))
    batch.set_drive_gains(kp, 100.0)
    batch.set_drive_targets(targets)
    batch.set_armature(rng.uniform(0.0, 0.05, (N, nv)))
    batch.set_link_mass("link3", rng.uniform(0.8, 1.2, N) * 2.0)
    batch.set_joint_friction(rng.uniform(0.0, 0.5, (N, nv)), 0.2, 0.1)


def test_lanes_equal_the_scalar_batch_and_every_width_the_same_bits():
    proto = arm_prototype()
    nv = proto.model.nv
    scalar = fd.Batch(proto, N)
    scalar.lanes = False
    assert scalar.step_path == "scalar: lanes off (set_lanes)"
    randomise(scalar, np.random.default_rng(4), nv)
    limited = 0.0
    for _ in range(200):
        scalar.step()
        limited = max(limited, np.max(np.abs(scalar.velocity_limit_force)))
    assert limited > 1.0  # the targets pull the joints past their URDF velocity limits
    results = []
    for isa in fd.available_simd_isas():
        lanes = fd.Batch(proto, N)
        lanes.isa = isa
        assert lanes.isa == isa and lanes.q.shape == (N, proto.model.nq)
        randomise(lanes, np.random.default_rng(4), nv)
        assert lanes.step_path == f"{isa} lanes"
        lanes.step(200)
        for a, b in ((lanes.q, scalar.q), (lanes.qd, scalar.qd),
                     (lanes.drive_force, scalar.drive_force),
                     (lanes.friction_force, scalar.friction_force),
                     (lanes.velocity_limit_force, scalar.velocity_limit_force)):
            assert np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b))) <= 1e-12
        results.append(np.array(lanes.qd))
        assert not lanes.qd.flags.writeable
    for r in results[1:]:
        assert r.tobytes() == results[0].tobytes()


def test_bad_input_and_unsupported_settings():
    proto = arm_prototype()
    batch = fd.Batch(proto, 3)
    with pytest.raises(ValueError, match="stiffness = -1"):
        batch.set_drive_gains(-1.0, 1.0, env_ids=[1])
    with pytest.raises(ValueError, match=r"env_ids\[1\] = 7 is out of range"):
        batch.set_qd(0.0, env_ids=[0, 7])
    with pytest.raises(ValueError, match="isa = 'avx9'"):
        batch.isa = "avx9"
    batch.isa = None  # the default again
    assert batch.width in (2, 4, 8) and in_lanes(batch.step_path)
    assert batch.step_path.startswith(f"{batch.isa} lanes")
    options = proto.options
    options.guard = fd.StepGuard(max_joint_step=0.1)
    proto.set_options(options)
    assert in_lanes(fd.Batch(proto, 3).step_path)  # the lanes take the guard
    assert in_lanes(fd.Batch(self_colliding(), 3).step_path)  # and self-collision


def test_indices_and_sizes_are_checked():
    """An index is an integer in range (not a bool, not 2**40); a size stays within the bound
    that keeps the padding to whole blocks inside an int."""
    proto = arm_prototype()
    batch = fd.Batch(proto, 3)
    for index in (2**40, -1, 3, -(2**70)):
        with pytest.raises(ValueError, match=f"environment index.*{index}"):
            batch.simulation(index)
    for index in (True, 1.0, "1"):
        with pytest.raises(TypeError, match="environment index"):
            batch.simulation(index)
    assert batch.simulation(np.int64(2)).model.nv == proto.model.nv
    for count in (2**31 - 1, 2**24 + 1, 2**40):
        with pytest.raises(ValueError, match=f"count = {count}"):
            fd.Batch(proto, count)
    with pytest.raises(TypeError, match="count"):
        fd.Batch(proto, True)
    with pytest.raises(TypeError, match="environment index"):
        fd.Batch(proto, 2).sim(True)


def test_divergence_names_the_environment():
    proto = arm_prototype()
    for j in range(proto.model.nv):  # a velocity limit would scale 1e200 rad/s back to it
        proto.set_max_joint_velocity(j, np.inf)
    batch = fd.Batch(proto, 4)
    assert in_lanes(batch.step_path)
    batch.set_qd(1e200, env_ids=[2])
    with pytest.raises(RuntimeError, match="batch copy 2 \\(1 of 4"):
        batch.step(3)
    assert batch.step_count == [3, 3, 0, 3]
    assert list(batch.divergences()) == [2]


def test_the_simd_batch_shim_warns_and_refuses_what_the_lanes_do_not_step(monkeypatch):
    proto = arm_prototype()
    with pytest.warns(DeprecationWarning, match="use featherdrive.Batch"):
        batch = fd.SimdBatch(proto, 3, isa="sse2")
    assert isinstance(batch, fd.Batch) and batch.isa == "sse2"
    assert batch.step_path == "sse2 lanes"
    with pytest.warns(DeprecationWarning):
        assert in_lanes(fd.SimdBatch(self_colliding(), 3).step_path)
    monkeypatch.setenv("FEATHERDRIVE_SIMD", "scalar")
    with pytest.warns(DeprecationWarning), pytest.raises(
            ValueError, match="SimdBatch: FEATHERDRIVE_SIMD=scalar: not stepped in SIMD lanes"):
        fd.SimdBatch(proto, 3)


def test_a_floating_base_steps_in_lanes_as_each_simulation_alone():
    """arm7 on a floating base, as loaded, in the lanes: each environment within 1e-12 of the
    prototype stepped alone (the scalar step, another operation order), its root falling."""
    proto = arm_prototype(fixed_base=False)
    batch = fd.Batch(proto, 4)
    assert in_lanes(batch.step_path)
    alone = proto.copy()
    batch.step(300)
    alone.step(300)
    assert alone.q[2] < -1.0  # the root fell: 300 steps of 1/240 s in free fall
    for e in range(4):
        for lanes, scalar in ((batch.q[e], alone.q), (batch.qd[e], alone.qd)):
            scale = max(1.0, np.abs(scalar).max())
            np.testing.assert_allclose(lanes, scalar, rtol=0, atol=1e-12 * scale)
