"""A tiny pure-JAX task the trainer must solve in seconds: hold the action at a target.

Observation: a noisy constant (the policy has to learn to ignore the noise). Reward per
step: 1 - mean squared distance of the clipped action from the target. Success: the
final action within 0.1 (RMS) of the target. No physics, so training tests stay fast.
"""

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import Env, State


class ReachAction(Env):

  def __init__(self, target, obs_size: int = 3, episode_length: int = 10, action_size: int = 20):
    self.target = jnp.broadcast_to(jnp.asarray(target, jnp.float32), (action_size,))
    self._obs_size = obs_size
    self._action_size = action_size
    self.episode_length = episode_length

  @property
  def observation_size(self):
    return self._obs_size

  @property
  def action_size(self):
    return self._action_size

  @property
  def backend(self):
    return "jax"

  def _obs(self, key):
    return 1.0 + 0.1 * jax.random.normal(key, (self._obs_size,))

  def reset(self, rng):
    key, sub = jax.random.split(rng)
    zero = jnp.zeros(())
    metrics = {"success": zero, "diverged": zero, "reward/reach": zero}
    return State(pipeline_state=key, obs=self._obs(sub), reward=zero, done=zero,
                 metrics=metrics, info={})

  def step(self, state, action):
    key, sub = jax.random.split(state.pipeline_state)
    error = jnp.mean((jnp.clip(action, -1, 1) - self.target) ** 2)
    reward = 1.0 - error
    metrics = {"success": (error < 0.01).astype(jnp.float32), "diverged": jnp.zeros(()),
               "reward/reach": reward}
    return state.replace(pipeline_state=key, obs=self._obs(sub), reward=reward, metrics=metrics)


class StopOnSignal(ReachAction):
  """ReachAction whose episode also terminates (the task's own end, not the time limit) at
  a step whose action[0] exceeds 0.5, so envs of a batch end at different steps.
  Observation[0] is the number of steps taken in the episode."""

  def reset(self, rng):
    state = super().reset(rng)
    return state.replace(pipeline_state=(state.pipeline_state, jnp.zeros(())),
                         obs=state.obs.at[0].set(0.0))

  def step(self, state, action):
    key, t = state.pipeline_state
    state = super().step(state.replace(pipeline_state=key), action)
    return state.replace(pipeline_state=(state.pipeline_state, t + 1),
                         obs=state.obs.at[0].set(t + 1),
                         done=(action[0] > 0.5).astype(jnp.float32))


_SLIDER = """<mujoco><worldbody><body><joint name="slide" type="slide" axis="1 0 0"/>
<geom size="0.05" mass="1"/></body></worldbody><actuator><motor joint="slide"/></actuator>
</mujoco>"""


class PhysicsReach(ReachAction):
  """ReachAction that also steps MuJoCo's C engine through the native backend's host
  callback (a slider pushed by action[0]): a task whose every step runs the physics
  callback, as the hand's do, at the toy's cost. Observations and rewards are ReachAction's."""

  def __init__(self, target, **kwargs):
    import mujoco

    from discosyn_jax.env.physics.native import NativeBackend

    super().__init__(target, **kwargs)
    self.mj_model = mujoco.MjModel.from_xml_string(_SLIDER)
    self.physics = NativeBackend(self.mj_model, n_substeps=2, nthread=1)

  @property
  def backend(self):
    return "native"

  def reset(self, rng):
    state = super().reset(rng)
    zero = jnp.zeros((self.mj_model.nq,))
    return state.replace(pipeline_state=(state.pipeline_state, self.physics.init(zero, zero)))

  def step(self, state, action):
    key, physics = state.pipeline_state
    physics = self.physics.step(physics, action[:1])
    state = super().step(state.replace(pipeline_state=key), action)
    return state.replace(pipeline_state=(state.pipeline_state, physics))


# The toy tasks the experiment and report tests run, registered whole in the task registry
# (registry.register: a function that makes an env) so that they go through the one
# assembler as any task does.
TARGET = np.linspace(-0.8, 0.8, 20)


def _a():
  return ReachAction(TARGET)


def _b():
  return ReachAction(-TARGET, obs_size=5)


def _c():
  return ReachAction(0.5 * TARGET)


def _g():
  return ReachAction(0.3 * TARGET)


TOY_TASKS = {"a": _a, "b": _b, "c": _c, "g": _g}


def register() -> None:
  """Register the toy tasks a, b, c and g (again: a no-op)."""
  from discosyn_jax.tasks import registry

  for name, make in TOY_TASKS.items():
    registry.register(name, make)
