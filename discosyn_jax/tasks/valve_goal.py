"""Turn valve3 to a goal angle (the sparse task of the paper's exploration experiment).

Observation (30): the valve's (27, discosyn_jax/tasks/valve.py), then cos and sin of the goal angle and
the wrapped error goal - angle. Reward: 1 when |wrap(angle - goal)| < `threshold`, else 0
(`dense=True`, the debugging twin: 1 - |error| / pi, the same maximum). Success: within
the threshold in the episode's last state.

Numbers, and why: the goal lies `goal_min_turn`..`goal_max_turn` (0.9..1.5 rad)
counter-clockwise of the start angle (`both_ways=True`: either way), so that the start is
never rewarded (0.65 rad must be turned first) and a random policy almost never sees a
reward, while the scripted sweep, which turns valve3 up to 1.15 rad, reaches the nearer
goals. Counter-clockwise only because random flailing drifts valve3 clockwise by 0.25 rad
on average (p99 1.17 rad): with goals on both sides it met 6 % of them by drift
(docs/TASKS_NOTES.md). Threshold 0.25 rad as in ROBEL (PDDM uses 0.1).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp

from discosyn_jax.env.physics import PhysicsView
from discosyn_jax.env.task import Info
from discosyn_jax.tasks import common, valve


@dataclasses.dataclass(frozen=True)
class GoalValveConfig(valve.ValveConfig):
  threshold: float = 0.25  # rad: the reward's and success's band around the goal
  goal_min_turn: float = 0.9  # rad counter-clockwise from the start angle
  goal_max_turn: float = 1.5
  both_ways: bool = False  # goals clockwise of the start too
  dense: bool = False  # the debugging twin: 1 - |error| / pi instead of the 0/1 band


def default_config(**overrides) -> GoalValveConfig:
  return GoalValveConfig(**overrides)


class GoalValve(valve.Valve):  # the valves' fast physics and sweep

  def __init__(self, config: GoalValveConfig):
    super().__init__(config)
    common.require(0 < config.threshold < config.goal_min_turn <= config.goal_max_turn <= math.pi,
                   "need 0 < threshold < goal_min_turn <= goal_max_turn <= pi, got "
                   f"{config.threshold}, {config.goal_min_turn}, {config.goal_max_turn}")

  def initial_state(self, rng):
    k_start, k_turn, k_side = jax.random.split(rng, 3)
    qpos, qvel, info = super().initial_state(k_start)
    turn = jax.random.uniform(k_turn, (), minval=self.config.goal_min_turn, maxval=self.config.goal_max_turn)
    side = jnp.where(jax.random.bernoulli(k_side) | (not self.config.both_ways), 1.0, -1.0)
    return qpos, qvel, {**info, "goal": common.wrap_angle(info["start_angle"] + side * turn)}

  def error(self, view: PhysicsView, info: Info) -> jax.Array:
    """goal - angle, wrapped to [-pi, pi)."""
    return common.wrap_angle(info["goal"] - self.angle(view))

  def observation(self, view: PhysicsView, info: Info) -> jax.Array:
    goal = info["goal"]
    extra = jnp.stack([jnp.cos(goal), jnp.sin(goal), self.error(view, info)])
    return jnp.concatenate([super().observation(view, info), extra])

  def _within(self, view: PhysicsView, info: Info) -> jax.Array:
    return (jnp.abs(self.error(view, info)) < self.config.threshold).astype(jnp.float32)

  def reward_terms(self, prev: PhysicsView, view: PhysicsView, info: Info) -> dict[str, jax.Array]:
    if self.config.dense:
      return {"goal": 1.0 - jnp.abs(self.error(view, info)) / jnp.pi}
    return {"goal": self._within(view, info)}

  def success(self, view: PhysicsView, info: Info) -> jax.Array:
    return self._within(view, info)


# this family's tasks: the registry gives each to `register` (task, default config, summary)
TASKS = {
    "valve_goal": (GoalValve, default_config,
                   "turn the three-armed valve to a goal angle; reward 1 near it, else 0"),
    # its dense twin, for debugging
    "valve_goal_dense": (GoalValve, functools.partial(default_config, dense=True),
                         "valve_goal with a dense reward 1 - |error| / pi (debugging)"),
}
