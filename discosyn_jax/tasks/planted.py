"""Planted synergies: pure-JAX tasks (no physics) whose target postures lie in one known
subspace of the 20 actions, so that whether a decoder finds *the* synergy space of a task
set, and not just an adequate one, can be measured.

  planted span U    an orthonormal (20, rank) basis drawn once from SPAN_SEED: every run
                    and every task sees the same span
  task n            its own `task_rank`-dim plane of the span, U A_n (A_n: the first columns
                    of a random rotation of R^rank drawn from (SPAN_SEED, n)); the four
                    tasks' planes together span U, no one of them does
  an episode        a goal u ~ U[-1, 1]^task_rank, the observation; the target posture
                    a* = scale U A_n u, fixed for the episode (`scale` keeps |a*| <= 0.9:
                    a target is never clipped out of the span)
  reward per step   1 - |e|^2 / E|a*|^2, e = clip(a, -1, 1) - a*: 0 for a = 0 on average,
                    1 at the target
  success           |e| < tolerance * sqrt(E|a*|^2) at the episode's end

With `slack` only the part of e inside the planted span counts (e -> U U^T e): motion
outside it is free, so every decoder whose subspace projects onto the whole span is
adequate, as on the hand, where many subspaces turn the valves. Without slack the one
adequate subspace of `rank` dimensions is the span itself.

With `paid_within` > 0 the task pays nothing until an action lands near its target: the
reward is 1 - |e|^2 / E|a*|^2 where |e| < paid_within sqrt(E|a*|^2), else 0. A task that
pays only once it is found, as set #2's weight pull pays nothing until the weight lifts:
the planted place to watch what exploration does before a task is first paid.

With `outside` > 0 part of each target lies outside the span: a* = s U A_n u + s outside
u_1 w_n, w_n a unit direction orthogonal to the span, the task's own (u_1 the goal's first
coordinate, s keeping |a*| <= 0.9). No decoder of the span, and no constant posture, reaches
it: the motion a residual beside the synergies is for (agent/residual.py). Its share of the
target's power is outside^2 / (task_rank + outside^2).

With `excursion` > 0 the task pays only for reach, not for a posture: with r = clip(a, -1, 1)
. d_n, d_n the first axis of the task's plane (a unit direction inside the span), the reward
is clip((r - excursion) / EXCURSION_WIDTH, 0, 1), and success is r >= excursion. Nothing is
paid until the policy makes that excursion, and a narrower one is paid nothing at all: as
set #2's weight pull pays nothing until the pull is strong enough to lift the weight. The
goal is still observed and asks for nothing.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from brax.envs.base import Env, State

from discosyn_jax import checks
from discosyn_jax.checks import BadInput

SPAN_SEED = 26  # fixed; changing it plants another span in every run
ACTION_SIZE = 20
MAX_TARGET = 0.9  # the largest action a target asks for
EXCURSION_WIDTH = 0.5  # an excursion task's reward rises from 0 to 1 over this much more reach
# planted_found3: no reward until the error is below 0.7 of a typical target's size; the
# initial decoder's noise (std 0.3 on 20 actuators) alone is larger, so the task is first
# paid once the dense tasks have narrowed it (std ~0.2: a quarter of the steps at the target)
PAID_WITHIN = 0.7
# planted_reach3: paid only where the action reaches 1.0 along the task's direction: within
# what plane 2's dense targets ask along it (up to 1.46; planes 0 and 1: 0.40, 0.91), so a
# decoder serving the dense tasks reaches it; at the start 1.8-2.0 % of PPO's samples and
# 0.1-8 % of the synergy preset's (seeds 0-2) reach it, set before any run (2026-12-06)
REACH = 1.0
# planted_far3: the same task reaching 1.4, near the largest the dense targets ask along its
# direction (1.46), which a bounded z gives only near a corner of its box: at the start
# 0.15 % of PPO's samples, 0-0.75 % of the synergy preset's. Set after planted_reach3 was
# found at once by every synergy run (0.03-0.13 M env steps, 2026-12-06), before any run of it
REACH_FAR = 1.4


@dataclasses.dataclass(frozen=True)
class PlantedConfig:
  index: int = 0  # which task of the set: picks its plane of the span
  rank: int = 3  # dimension of the planted span
  task_rank: int = 2  # dimensions of the span one task's goals use
  slack: bool = False  # only the error inside the planted span counts
  episode_length: int = 10  # steps per episode; the goal is fixed for an episode
  tolerance: float = 0.25  # success: counted error below this fraction of a typical target
  # the part of each target outside the span, relative to one goal coordinate's part inside
  # (0: every target inside the span)
  outside: float = 0.0
  # the reward is paid only where the error is below this fraction of a typical target
  # (0: everywhere, the dense reward)
  paid_within: float = 0.0
  # the task pays only for the action's part along its own direction beyond this (0: a
  # posture task; module docstring)
  excursion: float = 0.0
  span_seed: int = SPAN_SEED

  def __post_init__(self):
    checks.fields(self)
    if not 1 <= self.rank <= ACTION_SIZE:
      raise BadInput(f"rank must be between 1 and {ACTION_SIZE}, not {self.rank}")
    if not 1 <= self.task_rank <= self.rank:
      raise BadInput(f"task_rank must be between 1 and rank ({self.rank}), not {self.task_rank}")
    if self.index < 0 or self.episode_length < 1 or self.tolerance <= 0:
      raise BadInput("index must not be negative, episode_length must be at least 1 and "
                     "tolerance positive")
    if self.outside < 0:
      raise BadInput(f"outside must not be negative, not {self.outside}")
    if not 0 <= self.paid_within <= 1:
      raise BadInput(f"paid_within must be between 0 and 1 (0: paid everywhere), not {self.paid_within}")
    if self.excursion < 0:
      raise BadInput(f"excursion must not be negative, not {self.excursion}")
    if self.excursion and (self.slack or self.outside or self.paid_within):
      raise BadInput("an excursion task pays for reach alone: slack, outside and paid_within "
                     "shape a posture task's pay, set them to 0")
    if self.outside and self.slack:
      raise BadInput("with slack the error outside the span counts for nothing: a target "
                     "outside it (outside > 0) would ask for nothing")


def default_config(**overrides) -> PlantedConfig:
  return PlantedConfig(**overrides)


@functools.cache
def span(rank: int = 3, seed: int = SPAN_SEED) -> np.ndarray:
  """The planted span: an orthonormal (20, rank) basis, the same for every call."""
  q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(ACTION_SIZE, rank)))
  return q.astype(np.float32)


def task_plane(config: PlantedConfig) -> np.ndarray:
  """(20, task_rank): the orthonormal basis of task `index`'s targets inside the span."""
  rng = np.random.default_rng((config.span_seed, config.index))
  rotation, _ = np.linalg.qr(rng.normal(size=(config.rank, config.rank)))
  return (span(config.rank, config.span_seed) @ rotation[:, :config.task_rank]).astype(np.float32)


def outside_direction(config: PlantedConfig) -> np.ndarray:
  """(20,): task `index`'s unit direction orthogonal to the planted span."""
  u = span(config.rank, config.span_seed)
  w = np.random.default_rng((config.span_seed, config.index, 1)).normal(size=ACTION_SIZE)
  w = w - u @ (u.T @ w)
  return (w / np.linalg.norm(w)).astype(np.float32)


class PlantedEnv(Env):
  """One planted task with Brax's Env interface (module docstring); `backend` and `hand` are
  accepted and ignored: there is no physics and no hand."""

  def __init__(self, config: PlantedConfig, backend: str = "auto", hand: str = ""):
    del backend, hand
    self.config = config
    self.episode_length = config.episode_length
    self.planted_span = span(config.rank, config.span_seed)  # what the decoder should find
    plane = task_plane(config)
    if config.outside:  # the first goal coordinate also moves the target off the span
      plane = plane.copy()
      plane[:, 0] += config.outside * outside_direction(config)
    # the largest |a*_i| over the goal box is sum_j |plane_ij|
    self._targets = jnp.asarray(plane * (MAX_TARGET / np.abs(plane).sum(axis=1).max()))
    # E|a*|^2 for u ~ U[-1, 1]^k: the columns of _targets are orthogonal, each u_j has variance 1/3
    self._target_power = float((np.asarray(self._targets) ** 2).sum() / 3)
    self._projector = jnp.asarray(self.planted_span @ self.planted_span.T)
    self._direction = jnp.asarray(task_plane(config)[:, 0])  # what an excursion task pays along

  @property
  def observation_size(self) -> int:
    return self.config.task_rank

  @property
  def action_size(self) -> int:
    return ACTION_SIZE

  @property
  def backend(self) -> str:
    return "jax"

  def reset(self, rng: jax.Array) -> State:
    goal = jax.random.uniform(rng, (self.config.task_rank,), minval=-1.0, maxval=1.0)
    zero = jnp.zeros(())
    metrics = {"success": zero, "diverged": zero, "reward/reach": zero}
    return State(pipeline_state={"target": self._targets @ goal}, obs=goal, reward=zero,
                 done=zero, metrics=metrics, info={})

  def step(self, state: State, action: jax.Array) -> State:
    if self.config.excursion:
      return self._excursion_step(state, action)
    error = jnp.clip(action, -1.0, 1.0) - state.pipeline_state["target"]
    if self.config.slack:
      error = self._projector @ error
    power = jnp.sum(error ** 2)
    reward = 1.0 - power / self._target_power
    if self.config.paid_within:  # nothing paid until the action is near its target
      reward = jnp.where(power < self.config.paid_within ** 2 * self._target_power, reward, 0.0)
    success = (power < self.config.tolerance ** 2 * self._target_power).astype(jnp.float32)
    metrics = {**state.metrics, "success": success, "reward/reach": reward}
    return state.replace(reward=reward, metrics=metrics)

  def _excursion_step(self, state: State, action: jax.Array) -> State:
    reach = jnp.clip(action, -1.0, 1.0) @ self._direction
    reward = jnp.clip((reach - self.config.excursion) / EXCURSION_WIDTH, 0.0, 1.0)
    success = (reach >= self.config.excursion).astype(jnp.float32)
    metrics = {**state.metrics, "success": success, "reward/reach": reward}
    return state.replace(reward=reward, metrics=metrics)


def _task(index: int, slack: bool, paid_within: float = 0.0, excursion: float = 0.0) -> tuple:
  """One task of the bed as the registry's `register` takes it: the env class (built from
  its config alone), its default config and its summary."""
  what = "only the error inside the span counts" if slack else "the whole error counts"
  if paid_within:
    what += f"; paid only within {paid_within:g} of a typical target"
  summary = f"reach a posture in plane {index} of the planted 3-D span; {what}"
  if excursion:
    summary = (f"reach beyond {excursion:g} along the first axis of plane {index} of the "
               "planted 3-D span; paid nothing short of it")
  config = functools.partial(default_config, index=index, slack=slack, paid_within=paid_within,
                             excursion=excursion)
  return PlantedEnv, config, summary


# the bed's tasks (one span, a plane per task): the registry gives each to `register`
TASKS = {
    **{f"planted{n}": _task(n, slack=False) for n in range(4)},
    **{f"planted_slack{n}": _task(n, slack=True) for n in range(4)},
    # a task of the bed that pays nothing until it is found (planted_found's fourth)
    "planted_found3": _task(3, slack=False, paid_within=PAID_WITHIN),
    # a task of the bed paid only for an excursion (planted_reach's and planted_far's fourth)
    "planted_reach3": _task(3, slack=False, excursion=REACH),
    "planted_far3": _task(3, slack=False, excursion=REACH_FAR),
}
