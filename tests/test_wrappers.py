"""The training auto-reset when some envs of the batch finish and others do not."""

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.wrappers.training import EpisodeWrapper, VmapWrapper

from discosyn_jax.env import wrappers
from tests.toy_env import StopOnSignal


def test_only_the_finished_envs_are_reset():
  """Six envs, episodes of at most 3 steps; env 0 stops itself at step 1, env 1 at step 2,
  the time limit ends the others at step 3 and env 0's second episode at step 4. Each env
  is reset at its own ends and nowhere else; the rest step on exactly as they would
  without the auto-reset."""
  base = StopOnSignal(0.0, obs_size=4, episode_length=3)
  env = wrappers.for_training(base)
  plain = VmapWrapper(EpisodeWrapper(base, 3, action_repeat=1))
  step, plain_step = jax.jit(env.step), jax.jit(plain.step)
  state = env.reset(jax.random.split(jax.random.PRNGKey(0), 6))
  stop_at = {1: [0], 2: [1], 3: [], 4: []}  # at step t, these envs signal the end
  ended = {1: [0], 2: [1], 3: [2, 3, 4, 5], 4: [0]}
  truncated = {1: [], 2: [], 3: [2, 3, 4, 5], 4: [0]}
  starts = {i: [np.asarray(state.obs[i])] for i in range(6)}
  for t in (1, 2, 3, 4):
    action = jnp.zeros((6, 20)).at[jnp.array(stop_at[t], int), 0].set(1.0)
    without_reset = plain_step(state, action)
    new = step(state, action)
    done = np.flatnonzero(np.asarray(new.done))
    assert sorted(done) == sorted(ended[t]), (t, done)
    np.testing.assert_array_equal(np.flatnonzero(np.asarray(new.info["truncation"])),
                                  sorted(truncated[t]))
    for i in range(6):
      if i in ended[t]:  # a fresh episode: step count 0, a new initial observation
        assert float(new.obs[i, 0]) == 0.0 and float(new.info["steps"][i]) == 0.0
        assert not np.allclose(new.obs[i], starts[i][-1])
        starts[i].append(np.asarray(new.obs[i]))
      else:  # untouched: exactly the plain step
        jax.tree.map(lambda a, b: np.testing.assert_array_equal(a[i], b[i]),
                     (new.obs, new.pipeline_state, new.info["steps"]),
                     (without_reset.obs, without_reset.pipeline_state, without_reset.info["steps"]))
      # the finished step's reward and done are kept for the learner either way
      assert float(new.reward[i]) == float(without_reset.reward[i])
      assert float(new.done[i]) == float(without_reset.done[i])
    state = new
  # the episode counters: env 0's second episode lasted 3 steps; env 1's second and the
  # others' second episodes have run 2 and 1 steps
  assert [float(x) for x in state.info["episode_metrics"]["length"]] == [3, 2, 1, 1, 1, 1]


def test_pooled_reset_restarts_from_the_pool_without_resetting_the_env():
  """With a reset pool, a finished env restarts from one of the pool's initial states,
  the others step on, and the step never calls the env's reset (MJX: no mjx.forward)."""
  base = StopOnSignal(0.0, obs_size=4, episode_length=3)
  env = wrappers.for_training(base, reset_pool=True)
  keys = jax.random.split(jax.random.PRNGKey(0), 6)
  calls = []
  original = base.reset
  base.reset = lambda rng: calls.append(1) or original(rng)
  state = env.reset(keys)
  assert len(calls) == 1  # the state and its pool from one (batched) reset
  base.reset = original
  pool_obs = np.asarray(state.info["reset_pool"].obs)
  assert pool_obs.shape == (6, 4) and not np.allclose(pool_obs, np.asarray(state.obs))
  # the state is the one the same keys give without a pool
  np.testing.assert_array_equal(
      np.asarray(state.obs), np.asarray(wrappers.for_training(base).reset(keys).obs))
  calls = []
  base.reset = lambda rng: calls.append(1) or original(rng)
  step = jax.jit(env.step)
  starts = set()
  for t in range(12):  # env 0 signals the end every step: a new episode each time
    state = step(state, jnp.zeros((6, 20)).at[0, 0].set(1.0))
    assert float(state.info["steps"][0]) == 0.0
    row = np.flatnonzero(np.all(np.isclose(pool_obs, np.asarray(state.obs[0])), axis=1))
    assert row.size == 1  # its new episode starts from a pool state
    starts.add(int(row[0]))
  assert len(starts) > 2  # drawn at random, not always the same
  assert not calls  # traced without the env's reset
  np.testing.assert_array_equal(np.asarray(state.info["reset_pool"].obs), pool_obs)
