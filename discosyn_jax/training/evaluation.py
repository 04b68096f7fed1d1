"""The deterministic policy (head mean, decoder mean) on each task: the evaluations a run
logs, the episodes a video shows, the actions the sequential baselines fit and the t-SNE
draws. The Trainer jits `episodes` and `returns` once for its envs (`trainer.episodes`,
`trainer.returns`); the rest runs on the host."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from discosyn_jax.env.task import label


def episodes(trainer, params, normalizers, key, task: int, episodes: int, keep_states: bool = False,
             at_step=None):
  """`episodes` deterministic episodes of one task, in parallel: per step z, action, reward
  and `alive` (1 until the episode's end, that step included), and the env state after the
  step when `keep_states` (videos); per episode its return and final success. `at_step`:
  the train step whose residual weight the policy acts with (with a residual; None: its cap)."""
  env = trainer.eval_envs[task]
  state = env.reset(jax.random.split(key, episodes))
  zeros = jnp.zeros(episodes)

  def step(carry, _):
    state, alive, ret, success = carry
    z, a, _ = trainer.act(params, task, trainer.normalize(state.obs, normalizers[task]),
                          at_step=at_step)
    state = env.step(state, a)
    ret = ret + alive * state.reward
    ended = alive * state.done
    success = jnp.where(ended > 0, state.metrics["success"], success)
    out = dict(z=z, action=a, reward=state.reward, alive=alive)
    if keep_states:
      out["state"] = state
    return (state, alive * (1 - state.done), ret, success), out

  (_, _, ret, success), traj = jax.lax.scan(
      step, (state, jnp.ones_like(zeros), zeros, zeros), None,
      length=trainer.envs[task].episode_length)
  return traj, ret, success


def returns(trainer, params, normalizers, key, at_step=None, count: int | None = None):
  """{task: {"return", "success"}} of the deterministic policy, averaged over `count`
  (default `eval_envs`) episodes per task (`at_step`: as for `episodes`)."""
  out = {}
  for n, name in enumerate(trainer.config.tasks):
    key, sub = jax.random.split(key)
    _, ret, success = episodes(trainer, params, normalizers, sub, n,
                               count or trainer.config.eval_envs, at_step=at_step)
    out[name] = {"return": ret.mean(), "success": success.mean()}
  return out


def evaluate(trainer, state, closing: bool = False) -> dict[str, dict[str, float]]:
  """The evaluation of a state; its key depends on the step only, never on training's rng. A
  residual acts with the weight of the state's step: the policy as it trained. `closing`:
  the closing evaluation that ends a run, `closing_episodes` per task on episodes of their
  own (another key than the curve's evaluation at the same step)."""
  key = jax.random.fold_in(jax.random.PRNGKey(trainer.config.seed + 1), int(state.step))
  if closing:
    key = jax.random.fold_in(key, CLOSING_KEY)
  at_step = state.step if trainer.model.residual else None
  count = trainer.config.closing_episodes if closing else None
  out = trainer.returns(state.params, state.normalizers, key, at_step=at_step, count=count)
  return jax.tree.map(float, jax.device_get(out))


CLOSING_KEY = 1  # folded into the closing evaluation's key: its episodes are not the curve's


def rollouts(trainer, params, normalizers, key, episodes: int):
  """{task: per-step arrays (steps, episodes, ...) of z, action, reward, alive} of the
  deterministic policy: what the sequential baselines fit and the t-SNE shows."""
  keys = jax.random.split(key, len(trainer.envs))
  return {name: jax.device_get(trainer.episodes(params, normalizers, keys[n], task=n,
                                                episodes=episodes)[0])
          for n, name in enumerate(trainer.config.tasks)}


def format_table(results: dict[str, dict[str, float]], step: int, config, episodes: int | None = None,
                 what: str = "") -> str:
  """The evaluation table that ends a run (`what`: "closing " for its closing evaluation) and
  that `discosyn eval` prints; a task of one's own by its class (its path would push the
  columns apart)."""
  width = max(16, *(len(label(name)) for name in results))
  lines = [f"{what}evaluation at step {step} ({step * config.env_steps_per_train_step:,} env steps, "
           f"{episodes or config.eval_envs} deterministic episodes per task)",
           f"{'task':{width}s} {'success':>8s} {'return':>9s}"]
  for name, r in results.items():
    lines.append(f"{label(name):{width}s} {r['success']:8.1%} {r['return']:9.2f}")
  return "\n".join(lines)
