"""The hand environment: a Task on a physics backend, with Brax's `Env` interface.

Brax's training wrappers (episode length, auto-reset, vmap) work on it unchanged.
Actions are one per actuator of the hand (20 for ours) in [-1, 1]: ctrl = mid + a *
half-range of each actuator's ctrlrange.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
from brax.envs.base import Env, State

from discosyn_jax.checks import BadInput
from discosyn_jax.env import hands, physics
from discosyn_jax.env.task import Task, own_code


def _check_shapes(name: str, state: State) -> None:
  """A task's functions return one observation vector and a number per metric (a task of
  one's own is checked here, before anything is traced with it)."""
  if len(state.obs.shape) != 1:
    raise BadInput(f"{name}.observation returns shape {state.obs.shape}, not one vector")
  wrong = {k: v.shape for k, v in state.metrics.items() if v.shape != ()}
  if wrong:
    raise BadInput(f"{name}: success and each reward term are one number per state, not "
                   + ", ".join(f"{k} of shape {s}" for k, s in wrong.items()))


class HandEnv(Env):

  def __init__(self, task: Task, backend: str = "auto", hand: str | hands.Hand = hands.DEFAULT,
               **backend_kwargs):
    self.task = task
    self.hand = hands.load(hand)
    with own_code(task, self.hand):  # its edit_spec and bind
      self.mj_model = task.build_model(self.hand)
    self.physics = physics.make_backend(
        backend, self.mj_model, task.config.n_substeps, **backend_kwargs)
    lo, hi = (jnp.asarray(self.mj_model.actuator_ctrlrange[:, i], jnp.float32) for i in (0, 1))
    self._ctrl_mid, self._ctrl_half = (hi + lo) / 2, (hi - lo) / 2
    self.episode_length = task.config.episode_length
    self.dt = task.dt
    try:
      first = jax.eval_shape(self.reset, jax.random.key(0))
    except (TypeError, AttributeError, KeyError, IndexError) as err:
      raise BadInput(f"{type(task).__name__}: its functions failed on a fresh episode: "
                     f"{type(err).__name__}: {err}") from None
    self._obs_shape = first.obs.shape
    _check_shapes(type(task).__name__, first)

  @property
  def observation_size(self) -> int:
    return int(self._obs_shape[-1])

  @property
  def action_size(self) -> int:
    return int(self.mj_model.nu)

  @property
  def backend(self) -> str:
    return self.physics.name

  def action_to_ctrl(self, action: jax.Array) -> jax.Array:
    # a NaN action (a policy fed a task's NaN observation, which the train step names) holds
    # its actuator at mid-range: MuJoCo C would reset the simulation with a warning per env
    action = jnp.nan_to_num(action)
    return self._ctrl_mid + jnp.clip(action, -1.0, 1.0) * self._ctrl_half

  def reset(self, rng: jax.Array) -> State:
    with own_code(self.task, self.hand):
      return self._reset(rng)

  def _reset(self, rng: jax.Array) -> State:
    qpos, qvel, info = self.task.initial_state(rng)
    pstate = self.physics.init(qpos, qvel)
    view = self.physics.view(pstate)
    terms = self.task.reward_terms(view, view, info)
    zero = jnp.zeros(())
    metrics = {f"reward/{k}": jnp.zeros_like(v) for k, v in terms.items()}
    metrics.update(success=self.task.success(view, info), diverged=zero)
    return State(pstate, self.task.observation(view, info), zero, zero, metrics, info)

  def step(self, state: State, action: jax.Array) -> State:
    # one env takes one action; a batch goes through jax.vmap (a wrong shape would
    # otherwise surface as an XLA INTERNAL error inside the physics callback)
    if jnp.shape(action) != (self.action_size,):
      raise BadInput(f"an action of one env has shape ({self.action_size},), not "
                     f"{jnp.shape(action)}; step a batch of envs with jax.vmap")
    with own_code(self.task, self.hand):
      return self._step(state, action)

  def _step(self, state: State, action: jax.Array) -> State:
    info = state.info
    prev = self.physics.view(state.pipeline_state)
    pstate = self.physics.step(state.pipeline_state, self.action_to_ctrl(action))
    view = self.physics.view(pstate)
    # A diverged simulation ends its episode with zero reward and success and a finite
    # observation; the wrapper's reset replaces its state. Elsewhere a task's values pass as
    # they are: a NaN there is the task's own, and the train step names it.
    diverged = 1.0 - jnp.isfinite(jnp.concatenate([view.qpos, view.qvel])).all().astype(jnp.float32)
    terms = {k: jnp.where(diverged > 0, 0.0, v)
             for k, v in self.task.reward_terms(prev, view, info).items()}
    reward = sum(terms.values())
    done = jnp.maximum(self.task.terminated(view, info), diverged)
    obs = self.task.observation(view, info)
    obs = jnp.where(diverged > 0, jnp.nan_to_num(obs, posinf=0.0, neginf=0.0), obs)
    # the state's metrics updated, not replaced: keys that wrappers add (Brax's EvalWrapper
    # adds "reward") must keep the state's structure through Brax's scans
    metrics = {**state.metrics, **{f"reward/{k}": v for k, v in terms.items()}}
    metrics.update(success=jnp.where(diverged > 0, 0.0, self.task.success(view, info)),
                   diverged=diverged)
    return state.replace(pipeline_state=pstate, obs=obs, reward=reward, done=done, metrics=metrics)
