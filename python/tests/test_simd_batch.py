"""fd.SimdBatch: environments in SIMD lanes equal the scalar Batch with the same per-environment
parameters within 1e-12, every width gives the same bits, and bad input raises ValueError."""
import numpy as np
import pytest

import featherdrive as fd

N = 11  # not a multiple of any width


def arm_prototype():
    """examples/arm7.urdf as loaded: its URDF velocity limits stay on."""
    model = fd.load_urdf(fd.example_path("arm7.urdf")).model
    return fd.Simulation(model, dt=1 / 240, solver="tgs", position_iterations=4,
                         stiffness=2e4, damping=100.0)


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
    randomise(scalar, np.random.default_rng(4), nv)
    limited = 0.0
    for _ in range(200):
        scalar.step()
        limited = max(limited, np.max(np.abs(scalar.velocity_limit_force)))
    assert limited > 1.0  # the targets pull the joints past their URDF velocity limits
    results = []
    for isa in fd.available_simd_isas():
        simd = fd.SimdBatch(proto, N, isa=isa)
        assert simd.isa == isa and simd.q.shape == (N, proto.model.nq)
        randomise(simd, np.random.default_rng(4), nv)
        simd.step(200)
        for a, b in ((simd.q, scalar.q), (simd.qd, scalar.qd),
                     (simd.drive_force, scalar.drive_force),
                     (simd.friction_force, scalar.friction_force),
                     (simd.velocity_limit_force, scalar.velocity_limit_force)):
            assert np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b))) <= 1e-12
        results.append(np.array(simd.qd))
        assert not simd.qd.flags.writeable
    for r in results[1:]:
        assert r.tobytes() == results[0].tobytes()


def test_bad_input_and_unsupported_settings():
    proto = arm_prototype()
    batch = fd.SimdBatch(proto, 3)
    with pytest.raises(ValueError, match="stiffness = -1"):
        batch.set_drive_gains(-1.0, 1.0, env_ids=[1])
    with pytest.raises(ValueError, match=r"env_ids\[1\] = 7 is out of range"):
        batch.set_qd(0.0, env_ids=[0, 7])
    with pytest.raises(ValueError, match="isa = 'avx9'"):
        fd.SimdBatch(proto, 3, isa="avx9")
    proto.set_drive_delay(2, 2)
    with pytest.raises(ValueError, match="joint 'joint3' has drive delay 2"):
        fd.SimdBatch(proto, 3)


def test_indices_and_sizes_are_checked():
    """An index is an integer in range (not a bool, not 2**40); a size stays within the bound
    that keeps the padding to whole blocks inside an int."""
    proto = arm_prototype()
    batch = fd.SimdBatch(proto, 3)
    for index in (2**40, -1, 3, -(2**70)):
        with pytest.raises(ValueError, match=f"environment index.*{index}"):
            batch.simulation(index)
    for index in (True, 1.0, "1"):
        with pytest.raises(TypeError, match="environment index"):
            batch.simulation(index)
    assert batch.simulation(np.int64(2)).model.nv == proto.model.nv
    for count in (2**31 - 1, 2**24 + 1, 2**40):
        with pytest.raises(ValueError, match=f"count = {count}"):
            fd.SimdBatch(proto, count)
        with pytest.raises(ValueError, match=f"count = {count}"):
            fd.Batch(proto, count)
    with pytest.raises(TypeError, match="count"):
        fd.SimdBatch(proto, True)
    with pytest.raises(TypeError, match="environment index"):
        fd.Batch(proto, 2).sim(True)


def test_divergence_names_the_environment():
    proto = arm_prototype()
    for j in range(proto.model.nv):  # a velocity limit would scale 1e200 rad/s back to it
        proto.set_max_joint_velocity(j, np.inf)
    batch = fd.SimdBatch(proto, 4)
    batch.set_qd(1e200, env_ids=[2])
    with pytest.raises(RuntimeError, match="environment 2 \\(1 of 4"):
        batch.step(3)
    assert batch.step_count == [3, 3, 0, 3]
    assert list(batch.divergences()) == [2]
