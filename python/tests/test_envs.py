"""featherdrive_envs.ReachEnv against its contract (Gymnasium's VectorEnv signatures, next-step
autoreset, seeding) and examples/python/reach_policy_search.py on a short run."""
import importlib.util

import numpy as np
import pytest

import featherdrive as fd
import featherdrive_envs
from conftest import ARM, ROOT


def make(n=4, **kw):
    kw.setdefault("seed", 7)
    return featherdrive_envs.ReachEnv(n, **kw)


def test_spaces_shapes_and_dtypes():
    env = make(3)
    assert env.observation_space.shape == (3, 20) and env.action_space.shape == (3, 7)
    assert env.single_observation_space.shape == (20,) and env.single_action_space.shape == (7,)
    assert np.all(env.action_space.low == -1.0) and np.all(env.action_space.high == 1.0)
    obs, infos = env.reset()
    assert obs.shape == (3, 20) and obs.dtype == np.float64 and isinstance(infos, dict)
    assert env.observation_space.contains(obs)
    out = env.step(np.zeros((3, 7)))
    assert len(out) == 5
    obs, rewards, terminated, truncated, infos = out
    assert obs.shape == (3, 20) and rewards.shape == (3,) and rewards.dtype == np.float64
    assert terminated.dtype == bool and truncated.dtype == bool and terminated.shape == (3,)
    with pytest.raises(ValueError, match=r"actions have shape \(7,\)"):
        env.step(np.zeros(7))
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full((3, 7), np.nan))
    with pytest.raises(ValueError, match="num_envs"):
        featherdrive_envs.ReachEnv(0)
    env.close()


def test_observation_and_reward_are_the_closed_form_of_the_state():
    env = make(2, action_cost=0.01)
    obs, _ = env.reset()
    a = np.full((2, 7), 0.5)
    a[1] = -2.0  # clipped to -1
    obs, rewards, *_ = env.step(a)
    batch = env.batch
    q, qd = np.array(batch.q), np.array(batch.qd)
    np.testing.assert_array_equal(obs[:, :7], q)
    np.testing.assert_array_equal(obs[:, 7:14], qd)
    for i in range(2):
        # The hand from the URDF chain: link7's origin plus R (0, 0, 0.06), by the module's
        # kinematics of a fresh model (the same file read again).
        model = fd.load_urdf(str(ARM)).model
        R, p = fd.link_pose(model, q[i], "link7")
        hand = p + R @ np.array([0.0, 0.0, 0.06])
        np.testing.assert_allclose(obs[i, 14:17], hand, atol=1e-12)
        cost = 0.01 * np.sum(np.clip(a[i], -1, 1) ** 2)
        assert rewards[i] == pytest.approx(-np.linalg.norm(hand - obs[i, 17:20]) - cost, abs=1e-12)
    # The drive targets are home + 0.5 * clipped action, inside the limits.
    expected = np.clip(env.home - 0.5, np.asarray(env.model.lower_limit), None)
    assert [batch.sim(1).drive(k).target_position for k in range(7)] == list(expected)


def test_each_env_steps_as_a_lone_simulation_with_its_gains():
    env = make(3)
    obs, _ = env.reset()
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1.2, 1.2, (4, 3, 7))
    model = fd.load_urdf(str(ARM)).model
    for i in range(3):
        u = env.gain_scale[i]
        sim = fd.Simulation(model, dt=1.0 / 120.0, solver="tgs", position_iterations=4,
                            stiffness=600.0 * u, damping=40.0 * np.sqrt(u))
        sim.set_q(obs[i, :7])
        alone = []
        for a in actions:
            target = np.clip(env.home + 0.5 * np.clip(a[i], -1, 1), model.lower_limit,
                             model.upper_limit)
            sim.set_drive_targets(target)
            sim.step(4)
            alone.append(np.concatenate([sim.q, sim.qd]))
        env_i = make(3)
        env_i.reset()
        batched = [env_i.step(a)[0][i, :14] for a in actions]
        # The env's Batch steps in SIMD lanes: within 1e-12 of the lone step.
        assert np.max(np.abs(np.array(alone) - np.array(batched))) <= 1e-12, i


def test_seeding_is_deterministic():
    def run(seed):
        env = make(3, seed=None)
        obs, _ = env.reset(seed=seed)
        rng = np.random.default_rng(0)
        out = [obs]
        for _ in range(5):
            out.append(env.step(rng.uniform(-1, 1, (3, 7)))[0])
        return np.array(out), env.gain_scale.copy()
    a, ga = run(11)
    b, gb = run(11)
    c, gc = run(12)
    assert a.tobytes() == b.tobytes() and ga.tobytes() == gb.tobytes()
    assert not np.array_equal(a, c)
    lo, hi = make(1).randomize_gains
    assert np.all((ga >= lo) & (ga <= hi)) and len(set(ga)) == 3  # per env


def test_truncation_and_next_step_autoreset():
    env = make(2, max_episode_steps=3)
    obs, _ = env.reset()
    goals0 = obs[:, 17:].copy()
    for k in range(3):
        obs, rewards, terminated, truncated, _ = env.step(np.zeros((2, 7)))
        assert not terminated.any()
        assert list(truncated) == [k == 2, k == 2]
    # The next step resets: action ignored, reward 0, neither flag, a new goal and episode.
    obs, rewards, terminated, truncated, _ = env.step(np.ones((2, 7)))
    assert list(rewards) == [0.0, 0.0] and not terminated.any() and not truncated.any()
    assert not np.array_equal(obs[:, 17:], goals0)
    assert np.all(obs[:, 7:14] == 0.0)  # the reset state, not stepped
    assert list(env.episode_steps) == [0, 0]
    assert [env.batch.sim(0).drive(k).target_position for k in range(7)] == list(env.home)
    # The new episode has its max_episode_steps = 3 steps after the reset step.
    for k in range(3):
        truncated = env.step(np.zeros((2, 7)))[3]
        assert list(truncated) == [k == 2, k == 2]


def test_next_step_autoreset_follows_gymnasium_rules(arm):
    """Gymnasium 1.x next-step autoreset, its rules as the expectation: the step after an env's
    step returned terminated (or truncated) resets that env, ignores its action, does not step its
    physics and returns its reset observation (q drawn about home, qd = 0) with reward 0 and
    terminated = truncated = False; the next step is the new episode's first; the other envs
    step as usual in the same call."""
    probe = make(2)
    probe.reset()
    distance = probe.step(np.zeros((2, 7)))[4]["distance"]
    assert distance[0] != distance[1]
    done, other = int(np.argmin(distance)), int(np.argmax(distance))
    radius = distance.mean()  # the same run where only env `done` reaches its goal at step 1

    def run_to_the_reset(action_of_done):
        env = make(2, success_radius=radius)
        env.reset()
        terminated = env.step(np.zeros((2, 7)))[2]
        assert list(terminated) == [i == done for i in range(2)]
        q_other = np.array(env.batch.q[other])
        actions = np.full((2, 7), 0.7)
        actions[done] = action_of_done
        return env, q_other, env.step(actions)

    env, q_other, (obs, rewards, terminated, truncated, _) = run_to_the_reset(0.7)
    assert rewards[done] == 0.0 and not terminated[done] and not truncated[done]
    q, qd = obs[done, :7], obs[done, 7:14]
    assert np.all(qd == 0.0) and np.all(np.abs(q - env.home) <= 0.1)
    R, p = fd.link_pose(arm, q, "link7")
    np.testing.assert_allclose(obs[done, 14:17], p + R @ [0.0, 0.0, 0.06], atol=1e-12)
    assert np.all(np.abs(obs[done, 17:] - env.hand_home) <= env.goal_range)
    # The other env made its step with its action in the same call.
    assert rewards[other] < 0.0 and not np.array_equal(obs[other, :7], q_other)
    # The ended env's action is ignored: another one gives the same bits.
    assert run_to_the_reset(-0.9)[2][0].tobytes() == obs.tobytes()
    # The reset observation is where the new episode starts: its first step is a lone
    # simulation's from (q, 0) with the episode's gains.
    u = env.gain_scale[done]
    sim = fd.Simulation(arm, dt=1.0 / 120.0, solver="tgs", position_iterations=4,
                        stiffness=600.0 * u, damping=40.0 * np.sqrt(u))
    sim.set_q(q)
    a = np.random.default_rng(4).uniform(-1, 1, (2, 7))
    sim.set_drive_targets(np.clip(env.home + 0.5 * a[done], arm.lower_limit, arm.upper_limit))
    sim.step(4)
    first = env.step(a)[0]
    # The env's Batch steps in SIMD lanes: within 1e-12 of the lone step.
    assert np.max(np.abs(np.concatenate([sim.q, sim.qd]) - first[done, :14])) <= 1e-12


def test_reaching_the_goal_terminates():
    env = make(2, success_radius=10.0)  # every hand starts within 10 m: success at once
    env.reset()
    _, _, terminated, truncated, _ = env.step(np.zeros((2, 7)))
    assert terminated.all() and not truncated.any()


def test_short_training_improves_and_plots(tmp_path):
    spec = importlib.util.spec_from_file_location(
        "reach_policy_search", ROOT / "examples" / "python" / "reach_policy_search.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    out = tmp_path / "curve.png"
    curve = example.main(["--iterations", "12", "--envs", "24", "--out", str(out)])
    assert len(curve) == 12
    assert np.mean(curve[-3:]) > curve[0] + 0.1 * abs(curve[0])
    assert out.stat().st_size > 1000 and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    again = example.main(["--iterations", "2", "--envs", "24", "--out", str(out)])
    assert list(again) == list(curve[:2])  # deterministic
