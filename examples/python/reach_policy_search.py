"""Trains a reaching policy for featherdrive_envs.ReachEnv (the 7-dof arm) by the cross-entropy
method, a numpy-only policy search, and saves its learning curve as a PNG.

The policy is linear in two features of the observation: the goal's offset from the hand's home
position and the hand's current error (goal - hand), both divided by the goal range, plus a bias:
action = clip(W f, -1, 1) with W of shape (7, 7). Each iteration draws one W per env from a
Gaussian, runs one episode in every env at once (each env its own goal and gains, drawn from a
seed that changes per iteration), keeps the best fifth and refits the Gaussian to them.
Everything is seeded: the same options give the same curve.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/reach_policy_search.py \\
        [--iterations 200] [--envs 64] [--seed 0] [--out out/reach_policy_search.png]

docs/examples.md records a full run's figures.
"""
import argparse
import os
import sys
import time

import numpy as np

import featherdrive_envs

ELITE_FRACTION = 0.2
INITIAL_SIGMA = 0.5
MIN_SIGMA = 0.02


def features(env, obs):
    """(N, 7): goal - home hand, goal - hand (both / goal range), 1."""
    hand, goal = obs[:, -6:-3], obs[:, -3:]
    scale = 1.0 / env.goal_range
    return np.hstack([(goal - env.hand_home) * scale, (goal - hand) * scale,
                      np.ones((len(obs), 1))])


def episode_returns(env, weights, seed):
    """The return of one episode per env, env i acting with weights[i] (7, 7)."""
    obs, _ = env.reset(seed=seed)
    returns = np.zeros(env.num_envs)
    running = np.ones(env.num_envs, dtype=bool)
    for _ in range(env.max_episode_steps):
        actions = np.clip(np.einsum("nij,nj->ni", weights, features(env, obs)), -1.0, 1.0)
        obs, rewards, terminated, truncated, _ = env.step(actions)
        returns += np.where(running, rewards, 0.0)
        running &= ~(terminated | truncated)
        if not running.any():
            break
    return returns


def train(iterations, envs, seed=0, env_seed=1000):
    """Runs the cross-entropy method; returns (mean return per iteration, final mean weights)."""
    env = featherdrive_envs.ReachEnv(envs, seed=env_seed)
    rng = np.random.default_rng(seed)
    shape = (env.action_space.shape[1], 7)
    mean, sigma = np.zeros(shape), np.full(shape, INITIAL_SIGMA)
    elites = max(2, int(round(ELITE_FRACTION * envs)))
    curve = []
    for it in range(iterations):
        weights = mean + sigma * rng.standard_normal((envs,) + shape)
        returns = episode_returns(env, weights, seed=env_seed + it)
        curve.append(float(returns.mean()))
        best = weights[np.argsort(returns)[-elites:]]
        mean, sigma = best.mean(axis=0), np.maximum(best.std(axis=0), MIN_SIGMA)
    env.close()
    return np.array(curve), mean


def save_curve(curve, path, envs):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(np.arange(1, len(curve) + 1), curve)
    ax.set_xlabel("iteration")
    ax.set_ylabel(f"mean episode return ({envs} envs)")
    ax.set_title("ReachEnv: cross-entropy method, linear policy")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--iterations", type=int, default=200)
    p.add_argument("--envs", type=int, default=64)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="out/reach_policy_search.png")
    args = p.parse_args(argv)
    if args.iterations < 1 or args.envs < 2:
        p.error("--iterations must be >= 1 and --envs >= 2")
    start = time.perf_counter()
    curve, _ = train(args.iterations, args.envs, args.seed)
    wall = time.perf_counter() - start
    save_curve(curve, args.out, args.envs)
    best = int(np.argmax(curve))
    print(f"{args.iterations} iterations x {args.envs} envs: mean return {curve[0]:.3f} at "
          f"iteration 1, {curve[-1]:.3f} at the last, best {curve[best]:.3f} at {best + 1}; "
          f"wall time {wall:.1f} s")
    print(f"learning curve: {args.out}")
    return curve


if __name__ == "__main__":
    main()
    sys.exit(0)
