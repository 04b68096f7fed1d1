"""The two physics backends: native equals plain mj_step; native and MJX agree; the GPU
path's training on the CPU (MJX under `Trainer.init` and one train step)."""

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from discosyn_jax import assemble, tasks
from discosyn_jax.config import TrainConfig
from discosyn_jax.env import hands, physics
from tests import helpers


def test_auto_picks_native_on_cpu():
  assert physics.resolve("auto") == "native"
  with pytest.raises(ValueError, match="unknown physics backend"):
    physics.resolve("bullet")


def test_native_equals_plain_mj_step_bit_for_bit():
  env = helpers.env("valve3")
  model = env.mj_model
  ctrls = np.random.default_rng(0).uniform(model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1], (30, model.nu))
  qpos0 = np.asarray(model.qpos0, np.float32) + 0.01

  def roll(ctrls):
    state = env.physics.init(jnp.asarray(qpos0), jnp.zeros(model.nv))
    return jax.lax.scan(lambda s, c: (env.physics.step(s, c),) * 2, state, ctrls)[1]

  states = jax.jit(roll)(jnp.asarray(ctrls, jnp.float32))
  data = mujoco.MjData(model)
  data.qpos[:] = qpos0
  mujoco.mj_forward(model, data)
  spec = mujoco.mjtState.mjSTATE_INTEGRATION
  expected = np.empty(mujoco.mj_stateSize(model, spec))
  for t in range(len(ctrls)):
    data.ctrl[:] = ctrls[t].astype(np.float32)  # the backend receives float32 controls
    for _ in range(env.task.config.n_substeps):
      mujoco.mj_step(model, data)
    mujoco.mj_getState(model, data, expected, spec)
    np.testing.assert_array_equal(np.asarray(states.raw[t]).view(np.float64), expected)
    np.testing.assert_array_equal(np.asarray(states.qpos[t]), data.qpos.astype(np.float32))


def test_native_and_mjx_trajectories_agree_on_valve3(valve3_on_both_backends):
  """50 control steps (2 s) of a grasp-and-sweep that turns valve3, on both backends.

  Tolerance: hand joints within 0.02 rad, valve angle within 0.05 rad. MJX computes in
  float32 and the C engine in float64, and their contact and solver code differ in
  rounding; the hand's trajectory stays within ~0.008 rad (measured), but the valve's dry
  friction (frictionloss) switches between stick and slip, which turns rounding into
  visible differences once the fingers push it (~0.025 rad measured on this sequence).
  """
  trajectories = {}
  for backend, (env, states) in valve3_on_both_backends.items():
    # MJX's reset and step, jitted: shaped, finite, the task's metrics, no episode ended
    assert states.obs.shape == (50, 27) and states.reward.shape == states.done.shape == (50,)
    for leaf in jax.tree.leaves((states.obs, states.reward, states.metrics)):
      assert np.isfinite(np.asarray(leaf)).all()
    assert set(states.metrics) == {"reward/turn", "reward/bias", "success", "diverged"}
    assert not np.asarray(states.done).any()
    trajectories[backend] = np.asarray(jax.vmap(env.physics.view)(states.pipeline_state).qpos)
  native, mjx = trajectories["native"], trajectories["mjx"]
  hand_q = hands.qpos_indices(env.mj_model)
  valve_q = env.task.valve_qpos
  assert native[-1, valve_q] - native[0, valve_q] > 0.2  # the fingers did turn it
  np.testing.assert_allclose(mjx[:, hand_q], native[:, hand_q], atol=0.02)
  np.testing.assert_allclose(mjx[:, valve_q], native[:, valve_q], atol=0.05)


def test_the_mjx_implementation_is_chosen_by_name_and_checked(monkeypatch):
  import importlib.util

  from discosyn_jax.env.physics import mjx_backend

  monkeypatch.setenv("DISCOSYN_MJX_IMPL", "cuda")
  with pytest.raises(ValueError, match="DISCOSYN_MJX_IMPL: unknown MJX implementation 'cuda'"):
    mjx_backend.default_impl()
  monkeypatch.setenv("DISCOSYN_MJX_IMPL", "jax")
  assert mjx_backend.default_impl() == "jax"
  monkeypatch.delenv("DISCOSYN_MJX_IMPL")  # unset: JAX's, whatever is installed (Warp is asked for)
  assert mjx_backend.default_impl() == "jax"
  if importlib.util.find_spec("warp") is None:  # MJX's Warp implementation needs warp-lang
    monkeypatch.setenv("DISCOSYN_MJX_IMPL", "warp")
    with pytest.raises(ValueError, match="needs warp-lang"):
      mjx_backend.default_impl()


def test_mjx_trainer_inits_and_trains_one_step():
  # `init` once ran MJX op by op (minutes per reset); it must be one jitted function, so this
  # test, at 2 envs, takes about as long as compiling the step
  trainer = assemble.trainer(TrainConfig(**helpers.ONE_MJX_STEP))
  assert trainer.envs[0].backend == "mjx"
  state = trainer.init()
  assert trainer._fresh_state._cache_size() == 1  # built by one compiled function
  assert state.env_states[0].obs.shape == (2, trainer.obs_sizes[0])
  helpers.assert_one_step_learns(trainer, state)
