"""MuJoCo Warp through MJX (`DISCOSYN_MJX_IMPL=warp`, the `.[warp]` extra) on Warp's CPU
device: each task follows MuJoCo C from the same states under the same actions; Warp and
MJX's JAX implementation agree; an outgrown buffer is reported, never silent; the batch
sizes the contact pool; one train step; the bench names it. Skipped where warp-lang is
absent.

The trajectories: 2 envs from a native reset, 50 control steps (2 s) of each task's
scripted motion (env/scripted.py; the dice's is the sweep, which moves the hand under the
cube), started on Warp from the native states (helpers.on_mjx). Every task on the shadow
hand; on leap16 a task of each kind (a valve, the free cube, the rope, the screw), which
keeps the file near two and a half minutes on 2 cores. Warp computes in float32, C in
float64: where a finger touches in one substep and not in the other, rounding becomes a
visible difference (MJX's JAX implementation is as far from C on every one of these, the
dice aside, where it is farther: docs/BENCHMARKS.md, "MuJoCo Warp").
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("warp", reason="MJX's Warp implementation needs warp-lang: "
                                   'pip install ".[warp]"')

from discosyn_jax import assemble, tasks  # noqa: E402
from discosyn_jax.config import TrainConfig  # noqa: E402
from discosyn_jax.env import hands, scripted  # noqa: E402
from discosyn_jax.env.hand_env import HandEnv  # noqa: E402
from discosyn_jax.env.physics.mjx_warp import WarpBackend  # noqa: E402
from tests import helpers  # noqa: E402

ENVS, STEPS = 2, 50
# max |qpos difference| Warp - MuJoCo C over these steps, (hand joints, object joints), rad or
# m: `python -m studies.warp_parity --batch 2 --steps 50` (2026-12-05). Tolerance: 3x, at
# least 2e-3 (float32 against float64 over 250 substeps).
MEASURED = {
    ("shadow20", "valve0"): (2.0e-4, 2.4e-6), ("shadow20", "valve1"): (2.5e-4, 3.1e-6),
    ("shadow20", "valve2"): (1.6e-1, 1.6e-1), ("shadow20", "valve3"): (6.7e-3, 1.4e-2),
    ("shadow20", "dice"): (2.6e-3, 1.1e-2), ("shadow20", "weight_pull"): (7.6e-5, 3.7e-5),
    ("shadow20", "screw"): (1.6e-2, 4.2e-2), ("shadow20", "valve_cylinder"): (4.6e-3, 2.1e-1),
    ("shadow20", "valve_cw"): (2.2e-2, 2.8e-2), ("shadow20", "screw_topdown"): (2.0e-4, 2.5e-3),
    ("shadow20", "valve_goal"): (6.1e-3, 1.5e-2),
    ("leap16", "valve3"): (4.2e-3, 4.0e-3), ("leap16", "dice"): (2.1e-4, 6.0e-8),
    ("leap16", "weight_pull"): (6.8e-5, 1.0e-4), ("leap16", "screw"): (4.3e-2, 7.2e-2),
}
# Warp against MJX's JAX implementation on valve3's 50-step grasp-and-sweep (test_backends.py):
# measured 8.5e-5 rad (hand), 8.6e-6 rad (valve)
JAX_TOLERANCE = 2e-3


def tolerance(measured: float) -> float:
  return max(3 * measured, 2e-3)


def warp_env(native):
  return HandEnv(native.task, backend="mjx", hand=native.hand, impl="warp")


def roll(env, start, actions):
  """qpos (T, B, nq) and the final state of `env` from `start` through `actions` (T, B, nu)."""
  step = lambda s, a: (jax.vmap(env.step)(s, a),) * 2
  last, states = jax.jit(lambda s, a: jax.lax.scan(step, s, a))(start, actions)
  return np.asarray(env.physics.view(states.pipeline_state).qpos), last


def scripted_run(name, hand):
  """(native env, its start states, the actions) of `name` on `hand`."""
  native = helpers.env(name, hand=hand)
  start = jax.jit(jax.vmap(native.reset))(jax.random.split(jax.random.PRNGKey(0), ENVS))
  motion = native.task.motion.actions(STEPS, native.dt, hand)
  return native, start, jnp.asarray(np.repeat(motion[:, None], ENVS, axis=1), jnp.float32)


def object_qpos(model) -> np.ndarray:
  """The qpos addresses of joints outside the hand (the object's)."""
  hand = set(int(i) for i in hands.qpos_indices(model))
  return np.array([i for i in range(model.nq) if i not in hand])


@pytest.mark.parametrize("hand, name", list(MEASURED))
def test_each_task_follows_mujoco_c_on_warp(hand, name):
  native, start, actions = scripted_run(name, hand)
  expected, _ = roll(native, start, actions)
  warp = warp_env(native)
  got, last = roll(warp, helpers.on_mjx(native, warp, start), actions)
  assert int(np.asarray(last.pipeline_state.overflow).max()) == 0  # no buffer outgrown
  assert np.isfinite(got).all()
  hand_q, object_q = hands.qpos_indices(native.mj_model), object_qpos(native.mj_model)
  on_hand, on_object = MEASURED[hand, name]
  np.testing.assert_allclose(got[..., hand_q], expected[..., hand_q], atol=tolerance(on_hand))
  np.testing.assert_allclose(got[..., object_q], expected[..., object_q],
                             atol=tolerance(on_object))


def test_warp_follows_jax_and_c_on_valve3(valve3_on_both_backends):
  """tests/test_backends.py's 50 control steps of valve3 (a grasp-and-sweep that turns it),
  on Warp from its own reset, beside MJX's JAX implementation and MuJoCo C."""
  native_env = valve3_on_both_backends["native"][0]
  warp = warp_env(native_env)
  actions = jnp.asarray(scripted.grasp_and_sweep(50, 0.04))

  def run(key):  # one env, no vmap: Warp's one-world path
    state = warp.reset(key)
    return jax.lax.scan(lambda s, a: (warp.step(s, a),) * 2, state, actions)[1]

  got = np.asarray(jax.jit(run)(jax.random.PRNGKey(3)).pipeline_state.qpos)
  hand_q, valve_q = hands.qpos_indices(native_env.mj_model), native_env.task.valve_qpos
  # C: test_backends.py's bounds for MJX's JAX implementation (Warp measured 0.0068, 0.020)
  for backend, on_hand, on_valve in (("mjx", JAX_TOLERANCE, JAX_TOLERANCE),
                                     ("native", 0.02, 0.05)):
    env, states = valve3_on_both_backends[backend]
    expected = np.asarray(jax.vmap(env.physics.view)(states.pipeline_state).qpos)
    np.testing.assert_allclose(got[:, hand_q], expected[:, hand_q], atol=on_hand)
    np.testing.assert_allclose(got[:, valve_q], expected[:, valve_q], atol=on_valve)


def test_an_outgrown_contact_pool_is_reported_not_silent(capfd):
  """A pool of one contact per env for the dice on the palm: Warp's own line says so, the
  env's overflow bits are set and its qpos is NaN, which the env counts as diverged."""
  native, start, actions = scripted_run("dice", "shadow20")
  warp = warp_env(native)
  warp.physics = WarpBackend(native.mj_model, native.task.config.n_substeps, contacts=1)
  _, last = roll(warp, helpers.on_mjx(native, warp, start), actions[:1])
  assert (np.asarray(last.pipeline_state.overflow) & warp.physics.buffers).all()
  assert np.asarray(last.metrics["diverged"]).all() and np.asarray(last.done).all()
  assert "overflow - please increase" in capfd.readouterr().out


def test_the_batch_sizes_the_contact_pool():
  native, start, actions = scripted_run("valve3", "shadow20")
  warp = warp_env(native)
  roll(warp, helpers.on_mjx(native, warp, start), actions[:1])
  assert set(warp.physics._datas) == {1, ENVS}  # one env (the env's own shape check), the batch
  assert warp.physics._datas[ENVS]._impl.naconmax == ENVS * warp.physics.contacts


def test_warp_trainer_inits_and_trains_one_step(monkeypatch):
  """tests/test_backends.py's MJX train step, on Warp, with the reset pool (the `gpu`
  scale's): the training wrappers select rows of the physics state."""
  monkeypatch.setenv("DISCOSYN_MJX_IMPL", "warp")
  trainer = assemble.trainer(TrainConfig(**helpers.ONE_MJX_STEP, reset_pool=True))
  assert trainer.envs[0].physics.impl == "warp"
  helpers.assert_one_step_learns(trainer, trainer.init())


def test_the_graph_mode_is_checked(monkeypatch):
  from discosyn_jax.env.physics import mjx_backend

  monkeypatch.setenv("DISCOSYN_MJX_IMPL", "warp")
  monkeypatch.setenv("DISCOSYN_WARP_GRAPH_MODE", "cuda")
  with pytest.raises(ValueError, match="DISCOSYN_WARP_GRAPH_MODE must be one of none, jax, warp"):
    mjx_backend.check_environment()  # the command line's check, before anything is built
  monkeypatch.setenv("DISCOSYN_WARP_GRAPH_MODE", "none")
  mjx_backend.check_environment()


def test_bench_names_the_implementation(capsys):
  from discosyn import cli

  argv = ["bench", "--backends", "mjx", "--impls", "warp", "--tasks", "valve1", "--batches", "2",
          "--no-train", "--repeats", "1"]
  assert cli.main(argv) == 0
  (row,) = [l.split("|") for l in capsys.readouterr().out.splitlines() if l.startswith("| mjx")]
  assert row[1].strip() == "mjx/warp" and float(row[5].replace(",", "")) > 0  # physics env/s
