"""A drawer knob to turn a quarter turn: a task of one's own, in one file outside the
package (docs/YOUR_TASK.md). Train it with

  discosyn train --tasks docs/examples/knob/knob_task.py:Knob valve3 --steps 200

The class names its object's MJCF file (`scene`), its config (`config_class`, a TaskConfig
with this task's own fields) and implements four pure JAX functions of the physics view.
"""

import dataclasses
import math
import pathlib

import jax.numpy as jnp

from discosyn_jax.env.task import Task, TaskConfig
from discosyn_jax.tasks import common


@dataclasses.dataclass(frozen=True)
class KnobConfig(TaskConfig):
  frictionloss: float = 0.05  # N m at the hinge
  max_rewarded_speed: float = 2.0  # rad/s
  success_turn: float = math.pi / 2  # rad, counter-clockwise seen from above


class Knob(Task):
  scene = pathlib.Path(__file__).with_name("knob.xml")
  config_class = KnobConfig
  summary = "turn a drawer knob a quarter turn counter-clockwise"

  def edit_spec(self, spec):
    spec.joint("knob").frictionloss = self.config.frictionloss

  def bind(self, model):
    self.hand = common.HandJoints(model)
    self.knob_qpos, self.knob_qvel = common.joint_address(model, "knob")

  def initial_state(self, rng):
    qpos = self.hand.start_qpos(rng, self.config.hand_noise)
    return qpos, self.hand.zero_qvel(), {}

  def observation(self, view, info):
    angle = view.qpos[self.knob_qpos]
    return jnp.concatenate([view.qpos[self.hand.qpos],
                            jnp.stack([jnp.cos(angle), jnp.sin(angle), view.qvel[self.knob_qvel]])])

  def reward_terms(self, prev, view, info):
    turned = view.qpos[self.knob_qpos] - prev.qpos[self.knob_qpos]
    return {"turn": common.capped_speed(turned, self.dt, self.config.max_rewarded_speed)}

  def success(self, view, info):
    return (view.qpos[self.knob_qpos] >= self.config.success_turn).astype(jnp.float32)
