"""Task set #1: turn a valve counter-clockwise (valve0..valve3: 0 to 3 arms).

Observation: hand joint angles (24), cos and sin of the valve angle, valve angular speed.
Reward (the same a, b for all four valves): r = a * clip(s * w, -w_max, w_max) + b, with w
the valve's mean angular velocity over the control step and s = +1 for counter-clockwise
(seen from above). Success: the net turn s * (angle_T - angle_0) reaches `success_turn`.

Numbers, and why (measured with experiments/valve_calibration.py, see docs/TASKS_NOTES.md):
the hinge gets the frictionloss and damping of a hand-operated valve so that random
flailing cannot spin it, and the rewarded speed is capped so that striking it is worth no
more than turning it steadily.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import mujoco

from discosyn_jax import hand
from discosyn_jax.physics import PhysicsView
from discosyn_jax.task import Info, Task, TaskConfig


@dataclasses.dataclass(frozen=True)
class ValveConfig(TaskConfig):
  arms: int = 3
  direction: float = 1.0  # +1: counter-clockwise seen from above, -1: clockwise
  reward_scale: float = 1.0  # a
  reward_bias: float = 0.0  # b
  max_rewarded_speed: float = 2.0  # rad/s, w_max
  damping: float = 0.5  # N m s / rad at the hinge
  frictionloss: float = 0.15  # N m at the hinge: it holds against light touches
  success_turn: float = math.pi / 4  # rad of net turn in the commanded direction


def default_config(**overrides) -> ValveConfig:
  return ValveConfig(**overrides)


class Valve(Task):

  def __init__(self, config: ValveConfig):
    super().__init__(config)
    if config.arms not in (0, 1, 2, 3):
      raise ValueError(f"a valve has 0 to 3 arms, not {config.arms}")
    self.scene = f"valve{config.arms}"

  def edit_spec(self, spec: mujoco.MjSpec) -> None:
    joint = spec.joint("valve")
    joint.damping = [self.config.damping, 0.0, 0.0]  # per-dof slots; a hinge uses the first
    joint.frictionloss = self.config.frictionloss

  def bind(self, model: mujoco.MjModel) -> None:
    self._hand_q = jnp.asarray(hand.qpos_indices(model))
    self.valve_qpos = int(model.jnt_qposadr[model.joint("valve").id])
    self.valve_qvel = int(model.jnt_dofadr[model.joint("valve").id])
    self._qpos0 = jnp.asarray(model.qpos0, jnp.float32)
    hand_ids = [model.joint(j).id for j in hand.JOINTS]
    self._lo = jnp.asarray(model.jnt_range[hand_ids, 0], jnp.float32)
    self._hi = jnp.asarray(model.jnt_range[hand_ids, 1], jnp.float32)
    self._nv = model.nv

  def initial_state(self, rng, model):
    k_hand, k_valve = jax.random.split(rng)
    noise = self.config.hand_noise * jax.random.uniform(k_hand, self._hand_q.shape, minval=-1, maxval=1)
    hand_q = jnp.clip(self._qpos0[self._hand_q] + noise, self._lo, self._hi)
    angle = jax.random.uniform(k_valve, (), minval=-jnp.pi, maxval=jnp.pi)
    qpos = self._qpos0.at[self._hand_q].set(hand_q).at[self.valve_qpos].set(angle)
    return qpos, jnp.zeros(self._nv, jnp.float32), {"start_angle": angle}

  def angle(self, view: PhysicsView) -> jax.Array:
    return view.qpos[self.valve_qpos]

  def observation(self, view: PhysicsView, info: Info) -> jax.Array:
    angle = self.angle(view)
    return jnp.concatenate([
        view.qpos[self._hand_q],
        jnp.stack([jnp.cos(angle), jnp.sin(angle), view.qvel[self.valve_qvel]]),
    ])

  def reward_terms(self, prev: PhysicsView, view: PhysicsView, info: Info) -> dict[str, jax.Array]:
    cfg = self.config
    speed = cfg.direction * (self.angle(view) - self.angle(prev)) / self.dt
    capped = jnp.clip(speed, -cfg.max_rewarded_speed, cfg.max_rewarded_speed)
    return {"turn": cfg.reward_scale * capped, "bias": jnp.full((), cfg.reward_bias)}

  def success(self, view: PhysicsView, info: Info) -> jax.Array:
    turned = self.config.direction * (self.angle(view) - info["start_angle"])
    return (turned >= self.config.success_turn).astype(jnp.float32)
