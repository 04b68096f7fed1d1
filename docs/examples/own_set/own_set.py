"""A task set of one's own, outside the package, whose motions are not the valves': press a
button down with the fingers bent at their knuckles, and rake a puck towards the palm with
the fingers curling back (docs/YOUR_TASK.md has the recipe). Train the two as one set:

  discosyn train --tasks docs/examples/own_set/own_set.py:Press \
      docs/examples/own_set/own_set.py:Rake --out runs/own_set

Each class names its object's MJCF file (`scene`) and implements the four pure JAX
functions of the physics; both read the hand through `common.HandJoints`, so they serve
any hand.
"""

import dataclasses
import pathlib

import jax.numpy as jnp

from discosyn_jax.env.task import Task, TaskConfig
from discosyn_jax.tasks import common

HERE = pathlib.Path(__file__).parent


class _Slide(Task):
  """What both tasks share: the hand, and one object on a slide joint named `joint`."""
  joint = ""

  def bind(self, model):
    self.hand = common.HandJoints(model)
    self.object_qpos, self.object_qvel = common.joint_address(model, self.joint)

  def initial_state(self, rng):
    return self.hand.start_qpos(rng, self.config.hand_noise), self.hand.zero_qvel(), {}


@dataclasses.dataclass(frozen=True)
class PressConfig(TaskConfig):
  success_depth: float = 0.04  # m the button is held down at the episode's end


class Press(_Slide):
  scene = HERE / "press.xml"
  config_class = PressConfig
  summary = "press a sprung button 4 cm down and hold it"
  joint = "button"

  def bind(self, model):
    super().bind(model)
    self.travel = float(-model.joint("button").range[0])

  def _depth(self, view):
    return -view.qpos[self.object_qpos]

  def observation(self, view, info):
    return jnp.concatenate([view.qpos[self.hand.qpos],
                            jnp.stack([self._depth(view) / self.travel, view.qvel[self.object_qvel]])])

  def reward_terms(self, prev, view, info):
    # the depth held, each step: pressing and holding pays, a tap barely does
    return {"depth": self._depth(view) / self.config.success_depth}

  def success(self, view, info):
    return (self._depth(view) >= self.config.success_depth).astype(jnp.float32)


@dataclasses.dataclass(frozen=True)
class RakeConfig(TaskConfig):
  success_distance: float = 0.05  # m towards the palm
  max_rewarded_speed: float = 0.2  # m/s


class Rake(_Slide):
  scene = HERE / "rake.xml"
  config_class = RakeConfig
  summary = "rake a puck 5 cm along its rail towards the palm"
  joint = "puck"

  def _raked(self, view):
    return -view.qpos[self.object_qpos]  # the rail's -y runs towards the palm

  def observation(self, view, info):
    return jnp.concatenate([view.qpos[self.hand.qpos],
                            jnp.stack([self._raked(view), view.qvel[self.object_qvel]])])

  def reward_terms(self, prev, view, info):
    moved = self._raked(view) - self._raked(prev)
    return {"rake": common.capped_speed(moved, self.dt, self.config.max_rewarded_speed)
            / self.config.max_rewarded_speed}

  def success(self, view, info):
    return (self._raked(view) >= self.config.success_distance).astype(jnp.float32)


@dataclasses.dataclass(frozen=True)
class RakeFarConfig(RakeConfig):
  success_distance: float = 0.09  # m: beyond what the neutral posture rakes (4.7 cm)


class RakeFar(Rake):
  """The rake, 9 cm: the neutral posture (every action 0) no longer does it (0 %); the four
  fingers' J2 curled with every other action at 0 does (all of 8 episodes); a uniform random
  policy 9-14 %."""
  config_class = RakeFarConfig
  summary = "rake a puck 9 cm along its rail towards the palm"
