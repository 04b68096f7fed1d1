"""Batched training envs: Brax's episode and vmap wrappers, and an auto-reset that draws a
fresh initial state for every episode.

Brax's own `AutoResetWrapper` puts a finished env back into the state of its first reset,
forever, so a task's random goals and initial hand noise would never change during
training. `FreshResetWrapper` keeps a key per env and resets finished envs from it.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from brax.envs.base import Env, State, Wrapper
from brax.envs.wrappers.training import EpisodeWrapper, VmapWrapper

# info entries of the finished episode that must survive the reset: GAE needs the
# truncation flag, the logs need the episode's sums
_KEEP_ON_RESET = ("truncation", "episode_done", "episode_metrics")


class FreshResetWrapper(Wrapper):
  """Batched auto-reset: an env whose step ends its episode comes back freshly reset.

  The returned state keeps the finished step's reward, done and metrics (they describe
  the transition) but holds the new episode's physics state and observation.

  With `pool`, a finished env restarts instead from one of B initial states made once at
  reset (B: the batch), drawn at random per episode: the step then holds no env reset,
  which on MJX is an `mjx.forward` per task for XLA to compile into the train step.
  """

  def __init__(self, env: Env, pool: bool = False):
    super().__init__(env)
    self.pool = pool

  def reset(self, rng: jax.Array) -> State:
    keys = jax.vmap(jax.random.split)(rng)  # (B, 2, 2): one to reset now, one to keep
    if not self.pool:
      state = self.env.reset(keys[:, 0])
    else:
      # the state and its pool from one reset of 2B rows: on MJX each reset is an
      # `mjx.forward` for XLA to compile, and init's compile is minutes on a GPU
      pool_keys = jax.vmap(jax.random.fold_in, (0, None))(keys[:, 1], 1)
      both = self.env.reset(jnp.concatenate([keys[:, 0], pool_keys]))
      batch = keys.shape[0]
      state = jax.tree.map(lambda x: x[:batch], both)
      state.info["reset_pool"] = jax.tree.map(lambda x: x[batch:], both)
    state.info["reset_key"] = keys[:, 1]
    return state

  def step(self, state: State, action: jax.Array) -> State:
    # a reset env already holds its fresh info (steps = 0); `done` described the last step
    state = self.env.step(state.replace(done=jnp.zeros_like(state.done)), action)
    return jax.lax.cond(state.done.any(), self._reset_done, lambda s: s, state)

  def _fresh(self, state: State, keys: jax.Array) -> State:
    if not self.pool:
      return self.env.reset(keys)
    pool = state.info["reset_pool"]
    # rows of this device's share of the pool (under shard_map the batch is split)
    rows = jax.tree.leaves(pool)[0].shape[0]
    pick = jax.vmap(lambda k: jax.random.randint(k, (), 0, rows))(keys)
    return jax.tree.map(lambda x: x[pick], pool)

  def _reset_done(self, state: State) -> State:
    keys = jax.vmap(jax.random.split)(state.info["reset_key"])
    fresh = self._fresh(state, keys[:, 0])
    done = state.done > 0

    def where_done(new, old):
      mask = jnp.reshape(done, done.shape + (1,) * (old.ndim - done.ndim))
      return jnp.where(mask, new, old)

    info = {k: (v if k in _KEEP_ON_RESET + ("reset_pool",) else
                jax.tree.map(where_done, fresh.info[k], v))
            for k, v in state.info.items() if k != "reset_key"}
    info["reset_key"] = where_done(keys[:, 1], state.info["reset_key"])
    return state.replace(
        pipeline_state=jax.tree.map(where_done, fresh.pipeline_state, state.pipeline_state),
        obs=where_done(fresh.obs, state.obs), info=info)


class EpisodeSuccess(Wrapper):
  """The env a user is given (`ds.make_env`): its `success` metric reported so that its sum
  over an episode is the success at the episode's last step, whatever step ends it; the
  success of the state itself is `info["success"]`.

  Brax's EvalWrapper sums each metric over an episode: `eval/episode_success` then reads as
  the share of episodes that end in success (0-1), as this package's evaluations do. Each
  step reports the change since what the episode has reported so far. A new episode starts
  from 0 at reset, and where Brax's EpisodeWrapper counts the steps, at its step 0 (Brax's
  auto-reset keeps the info of the episode before; action_repeat 1, Brax's default)."""

  def reset(self, rng: jax.Array) -> State:
    state = self.env.reset(rng)
    if "success" not in state.metrics:
      return state
    level = state.metrics["success"]
    info = {**state.info, "success": level, "success_reported": jnp.zeros_like(level)}
    return state.replace(metrics={**state.metrics, "success": jnp.zeros_like(level)}, info=info)

  def step(self, state: State, action: jax.Array) -> State:
    if "success_reported" not in state.info:
      return self.env.step(state, action)
    reported = state.info["success_reported"]
    if "steps" in state.info:
      reported = jnp.where(state.info["steps"] == 0, jnp.zeros_like(reported), reported)
    before, state = state, self.env.step(state, action)
    level = state.metrics["success"]
    info = {**state.info, "success": level, "success_reported": level}
    # keys that wrappers outside add (Brax's EvalWrapper: "reward") kept through their scans
    metrics = {**before.metrics, **state.metrics, "success": level - reported}
    return state.replace(metrics=metrics, info=info)


def for_training(env: Env, reset_pool: bool = False) -> Env:
  """Batched (reset takes keys of shape (B, 2)), time-limited at `env.episode_length`,
  auto-resetting with fresh initial states (or from a pool of them: FreshResetWrapper)."""
  return FreshResetWrapper(VmapWrapper(EpisodeWrapper(env, env.episode_length, action_repeat=1)),
                           pool=reset_pool)


def for_evaluation(env: Env) -> Env:
  """Batched and time-limited, no reset: one episode per env."""
  return VmapWrapper(EpisodeWrapper(env, env.episode_length, action_repeat=1))
