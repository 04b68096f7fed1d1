"""Lift a weight by pulling the soft rope tied to it (task set #2).

A 0.03 m, 50 g cube on a vertical slide rests on the floor; a rope of ten 3 g capsule links
joined by ball joints stands up from it to a handle bar under the fingers
(xml/objects/weight_pull.xml). Hooking the bar and pitching the wrist or curling the
fingers up lifts the weight.

Observation (32): hand joint angles (24), the weight's lift and lift speed, the handle's
position (3) and the direction of its bar (3).
Reward ([page]: r = m * cube height + n): `reward_scale` * lift + `reward_bias`, lift in m
above the rest position. Success: lift >= `success_lift` in the episode's last state.

Numbers, and why: m = 20 per metre makes a 0.05 m lift worth 1 per step, the scale of the
valves' rewards; success at 0.03 m (the task's specification). The rope's ball joints get a little
stiffness (0.02 N m / rad) so that it stands up to the hand instead of collapsing on the
weight, and it is soft enough for the fingers to bend; its links' armature keeps those
springs stable at the 4 ms step (docs/TASKS_NOTES.md has the measured figures).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco

from discosyn_jax.env import scripted
from discosyn_jax.env.physics import PhysicsView
from discosyn_jax.env.task import Info, Task, TaskConfig
from discosyn_jax.tasks import common

ROPE_LINKS = 10


@dataclasses.dataclass(frozen=True)
class WeightPullConfig(TaskConfig):
  reward_scale: float = 20.0  # m: per metre of lift
  reward_bias: float = 0.0  # n
  success_lift: float = 0.03  # m
  rope_stiffness: float = 0.02  # N m / rad at each ball joint
  rope_damping: float = 0.002  # N m s / rad


def default_config(**overrides) -> WeightPullConfig:
  return WeightPullConfig(**overrides)


class WeightPull(Task):
  scene = "weight_pull"
  # no fast physics: the rope failed every setting cheaper than the reference
  motion = scripted.Motion(scripted.hook_and_lift)

  def __init__(self, config: WeightPullConfig):
    super().__init__(config)
    common.require(config.success_lift > 0, f"success_lift must be > 0, not {config.success_lift}")
    common.require(config.rope_stiffness >= 0 and config.rope_damping >= 0,
                   f"rope stiffness and damping must be >= 0, not {config.rope_stiffness}, {config.rope_damping}")

  def edit_spec(self, spec: mujoco.MjSpec) -> None:
    for i in range(ROPE_LINKS):
      joint = spec.joint(f"rope{i}")
      joint.stiffness = [self.config.rope_stiffness, 0.0, 0.0]  # per-dof slots; a ball uses the first
      joint.damping = [self.config.rope_damping, 0.0, 0.0]

  def bind(self, model: mujoco.MjModel) -> None:
    self.hand = common.HandJoints(model)
    self.weight_qpos, self.weight_qvel = common.joint_address(model, "weight")
    sensor = model.sensor("handle_pos")
    self._handle = int(sensor.adr[0])  # handle_pos (3) then handle_axis (3)

  def initial_state(self, rng):
    return self.hand.start_qpos(rng, self.config.hand_noise), self.hand.zero_qvel(), {}

  def lift(self, view: PhysicsView) -> jax.Array:
    return view.qpos[self.weight_qpos]

  def observation(self, view: PhysicsView, info: Info) -> jax.Array:
    return jnp.concatenate([
        view.qpos[self.hand.qpos],
        jnp.stack([self.lift(view), view.qvel[self.weight_qvel]]),
        view.sensordata[self._handle:self._handle + 6],
    ])

  def reward_terms(self, prev: PhysicsView, view: PhysicsView, info: Info) -> dict[str, jax.Array]:
    cfg = self.config
    return {"lift": cfg.reward_scale * self.lift(view), "bias": jnp.full((), cfg.reward_bias)}

  def success(self, view: PhysicsView, info: Info) -> jax.Array:
    return (self.lift(view) >= self.config.success_lift).astype(jnp.float32)


# this family's task: the registry gives it to `register` (task, default config, summary)
TASKS = {"weight_pull": (WeightPull, default_config, "lift a weight by pulling up the rope tied to it")}
