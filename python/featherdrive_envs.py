"""Vector environments on featherdrive's Batch, with Gymnasium's VectorEnv method signatures
(reset, step, close, observation_space, action_space) but without importing gymnasium.

ReachEnv: N copies of the 7-dof arm (examples/arm7.urdf) whose hand must reach a goal point.
Autoreset is Gymnasium's next-step mode (its default since 1.0): the step that ends an episode
returns its last observation with terminated or truncated set; the next step() resets that env,
ignores its action, does not step its physics and returns the new episode's reset observation
(the one reset() would give: qd = 0) with reward 0 and terminated = truncated = False; the
episode's steps count from the step after it. docs/examples.md describes the environment and its numbers.
"""
import os

import numpy as np

import featherdrive as fd

__all__ = ["Box", "ReachEnv"]


class Box:
    """A box of shape `shape` with bounds low and high (Gymnasium's Box, as plain attributes)."""

    def __init__(self, low, high, shape, dtype=np.float64):
        self.shape = tuple(shape)
        self.dtype = np.dtype(dtype)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()

    def contains(self, x):
        x = np.asarray(x)
        return x.shape == self.shape and bool(np.all(x >= self.low) and np.all(x <= self.high))

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


class ReachEnv:
    """num_envs arms; each episode a goal point and drive gains are drawn per env.

    Observation (num_envs, 20): q (7), qd (7), hand position (3), goal (3), world frame, metres.
    Action (num_envs, 7) in [-1, 1]: drive target = home + action_scale * action (rad), clipped.
    Reward: -|hand - goal| - action_cost * |action|^2 per step. terminated: the hand within
    success_radius of the goal; truncated: max_episode_steps steps without that.
    Each episode every env's stiffness and damping are the nominal ones times a factor drawn
    uniformly from randomize_gains (damping times its square root: the same damping ratio).
    """

    hand_link = "link7"
    hand_point = (0.0, 0.0, 0.06)  # the tip of link7, in its frame
    home = np.array([0.0, 0.4, 0.0, 0.8, 0.0, 0.4, 0.0])
    stiffness = 600.0  # Nm/rad, nominal
    damping = 40.0  # Nms/rad, nominal

    def __init__(self, num_envs, urdf=None, decimation=4, dt=1.0 / 120.0, max_episode_steps=60,
                 seed=None, randomize_gains=(0.7, 1.3), goal_range=0.2, action_scale=0.5,
                 action_cost=0.01, success_radius=0.03):
        if int(num_envs) != num_envs or num_envs < 1:
            raise ValueError(f"ReachEnv: num_envs = {num_envs!r} must be an integer >= 1")
        if int(decimation) != decimation or decimation < 1:
            raise ValueError(f"ReachEnv: decimation = {decimation!r} must be an integer >= 1")
        if int(max_episode_steps) != max_episode_steps or max_episode_steps < 1:
            raise ValueError(
                f"ReachEnv: max_episode_steps = {max_episode_steps!r} must be an integer >= 1")
        lo, hi = randomize_gains
        if not 0.0 < lo <= hi:
            raise ValueError(f"ReachEnv: randomize_gains = {randomize_gains!r}: need 0 < lo <= hi")
        self.num_envs = int(num_envs)
        self.decimation = int(decimation)
        self.max_episode_steps = int(max_episode_steps)
        self.randomize_gains = (float(lo), float(hi))
        self.goal_range, self.action_scale = float(goal_range), float(action_scale)
        self.action_cost, self.success_radius = float(action_cost), float(success_radius)
        self.urdf = urdf if urdf is not None else fd.example_path("arm7.urdf")
        self.model = fd.load_urdf(os.fspath(self.urdf)).model
        if self.model.nv != 7 or self.model.floating_base():
            raise ValueError(f"ReachEnv: {self.urdf}: expected a fixed-base 7-dof arm, "
                             f"got nv = {self.model.nv}")
        self.dt = float(dt) * self.decimation  # one env step
        self.batch = fd.Batch(self.model, self.num_envs, dt=float(dt), solver="tgs",
                              position_iterations=4)
        self.batch.num_threads = 1  # small arms: threads cost more than they save
        self.lower = np.asarray(self.model.lower_limit)
        self.upper = np.asarray(self.model.upper_limit)
        self.hand_home = fd.frame_position(self.model, self.home, self.hand_link, self.hand_point)
        nv = self.model.nv
        self.single_observation_space = Box(-np.inf, np.inf, (2 * nv + 6,))
        self.single_action_space = Box(-1.0, 1.0, (nv,))
        self.observation_space = Box(-np.inf, np.inf, (self.num_envs, 2 * nv + 6))
        self.action_space = Box(-1.0, 1.0, (self.num_envs, nv))
        self.metadata = {"autoreset_mode": "next_step"}
        self._rng = np.random.default_rng(seed)
        self.goal = np.zeros((self.num_envs, 3))
        self.gain_scale = np.ones(self.num_envs)
        self.episode_steps = np.zeros(self.num_envs, dtype=np.int64)
        self._needs_reset = np.zeros(self.num_envs, dtype=bool)
        self._started = False

    # ---- the VectorEnv methods ---------------------------------------------------------------
    def reset(self, seed=None, options=None):
        """Resets every env; seed (int) reseeds the generator. Returns (obs, infos)."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        self._reset_envs(np.arange(self.num_envs))
        self._started = True
        return self._observe(), {}

    def step(self, actions):
        """actions (num_envs, 7); returns (obs, rewards, terminated, truncated, infos)."""
        if not self._started:
            raise RuntimeError("ReachEnv.step: call reset() first")
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(f"ReachEnv.step: actions have shape {a.shape}, expected "
                             f"{self.action_space.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError("ReachEnv.step: actions must be finite")
        a = np.clip(a, -1.0, 1.0)
        resetting = np.flatnonzero(self._needs_reset)
        a[resetting] = 0.0
        targets = np.clip(self.home + self.action_scale * a, self.lower, self.upper)
        self.batch.set_drive_targets(targets)
        # The Batch steps every env; one that ended is then reset, so its physics does not move:
        # it returns its reset observation (the new episode's step 0), as Gymnasium's next-step
        # autoreset does.
        self.batch.step(self.decimation)
        self.episode_steps += 1
        if resetting.size:
            self._reset_envs(resetting)
        obs = self._observe()
        distance = np.linalg.norm(obs[:, -6:-3] - self.goal, axis=1)
        rewards = -distance - self.action_cost * np.sum(a * a, axis=1)
        terminated = distance < self.success_radius
        truncated = ~terminated & (self.episode_steps >= self.max_episode_steps)
        rewards[resetting], terminated[resetting], truncated[resetting] = 0.0, False, False
        self._needs_reset = terminated | truncated
        return obs, rewards, terminated, truncated, {"distance": distance}

    def close(self):
        self.batch = None

    # ---- internals ---------------------------------------------------------------------------
    def _reset_envs(self, ids):
        n, nv = len(ids), self.model.nv
        self.goal[ids] = self.hand_home + self._rng.uniform(-self.goal_range, self.goal_range,
                                                            (n, 3))
        self.gain_scale[ids] = self._rng.uniform(*self.randomize_gains, n)
        q = self.home + self._rng.uniform(-0.1, 0.1, (n, nv))
        self.batch.reset(ids, q, np.zeros((n, nv)))
        scale = self.gain_scale[ids, None] * np.ones((1, nv))
        self.batch.set_drive_gains(self.stiffness * scale, self.damping * np.sqrt(scale),
                                   env_ids=ids)
        self.episode_steps[ids] = 0
        self._needs_reset[ids] = False

    def _observe(self):
        hand = self.batch.frame_positions(self.hand_link, self.hand_point)
        return np.hstack([self.batch.q, self.batch.qd, hand, self.goal])
