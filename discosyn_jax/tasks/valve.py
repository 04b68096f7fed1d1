"""Turn a valve: task set #1 (valve0..valve3: 0 to 3 arms) and its unseen variants
(valve_cylinder: a round wheel; valve_cw: valve3 turned clockwise).

Observation: hand joint angles (24), cos and sin of the valve angle, valve angular speed.
Reward (the same a, b for all valves): r = a * clip(s * w, -w_max, w_max) + b, with w the
valve's mean angular velocity over the control step and s = +1 for counter-clockwise (seen
from above), -1 for clockwise. Success: the net turn s * (angle_T - angle_0) reaches
`success_turn`.

Numbers, and why (measured with studies/valve_calibration.py, see docs/TASKS_NOTES.md):
the hinge gets the frictionloss and damping of a hand-operated valve so that random
flailing cannot spin it, and the rewarded speed is capped so that striking it is worth no
more than turning it steadily. The wheel keeps the valves' hinge, threshold and reward.
valve_cw needs a net clockwise turn of 1.2 rad (not pi/4): random flailing drifts valve3
clockwise by 0.25 rad on average, and met pi/4 clockwise in 22 % of episodes.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import mujoco

from discosyn_jax.env import scripted
from discosyn_jax.env.physics import PhysicsView
from discosyn_jax.env.task import Info, Task, TaskConfig
from discosyn_jax.tasks import common

SHAPES = ("arms", "wheel")


@dataclasses.dataclass(frozen=True)
class ValveConfig(TaskConfig):
  shape: str = "arms"  # "arms": valve<arms>; "wheel": the round valve_cylinder
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
  fast_physics = common.EIGHT_MS_STIFF

  def __init__(self, config: ValveConfig):
    super().__init__(config)
    common.require(config.shape in SHAPES, f"a valve's shape is one of {SHAPES}, not {config.shape!r}")
    common.require(config.arms in (0, 1, 2, 3), f"a valve has 0 to 3 arms, not {config.arms}")
    common.require(config.direction in (1.0, -1.0), f"direction is +1 or -1, not {config.direction}")
    common.require_hinge(config)
    self.scene = "valve_cylinder" if config.shape == "wheel" else f"valve{config.arms}"

  @property
  def motion(self) -> scripted.Motion:
    """The grasp-and-sweep in the valve's direction, on either hand (valve_cw: its mirror)."""
    direction = self.config.direction
    return scripted.Motion(options=dict(direction=direction), leap_direction=direction)

  def edit_spec(self, spec: mujoco.MjSpec) -> None:
    joint = spec.joint("valve")
    joint.damping = [self.config.damping, 0.0, 0.0]  # per-dof slots; a hinge uses the first
    joint.frictionloss = self.config.frictionloss

  def bind(self, model: mujoco.MjModel) -> None:
    self.hand = common.HandJoints(model)
    self.valve_qpos, self.valve_qvel = common.joint_address(model, "valve")

  def initial_state(self, rng):
    k_hand, k_valve = jax.random.split(rng)
    angle = jax.random.uniform(k_valve, (), minval=-jnp.pi, maxval=jnp.pi)
    qpos = self.hand.start_qpos(k_hand, self.config.hand_noise).at[self.valve_qpos].set(angle)
    return qpos, self.hand.zero_qvel(), {"start_angle": angle}

  def angle(self, view: PhysicsView) -> jax.Array:
    return view.qpos[self.valve_qpos]

  def observation(self, view: PhysicsView, info: Info) -> jax.Array:
    angle = self.angle(view)
    return jnp.concatenate([
        view.qpos[self.hand.qpos],
        jnp.stack([jnp.cos(angle), jnp.sin(angle), view.qvel[self.valve_qvel]]),
    ])

  def reward_terms(self, prev: PhysicsView, view: PhysicsView, info: Info) -> dict[str, jax.Array]:
    cfg = self.config
    turned = cfg.direction * (self.angle(view) - self.angle(prev))
    speed = common.capped_speed(turned, self.dt, cfg.max_rewarded_speed)
    return {"turn": cfg.reward_scale * speed, "bias": jnp.full((), cfg.reward_bias)}

  def success(self, view: PhysicsView, info: Info) -> jax.Array:
    turned = self.config.direction * (self.angle(view) - info["start_angle"])
    return (turned >= self.config.success_turn).astype(jnp.float32)


# this family's tasks: the registry gives each to `register` (task, default config, summary),
# the path a task of one's own takes
TASKS = {
    "valve0": (Valve, functools.partial(default_config, arms=0),
               "turn a bare vertical stem counter-clockwise"),
    "valve1": (Valve, functools.partial(default_config, arms=1),
               "turn a one-armed (L) valve counter-clockwise"),
    "valve2": (Valve, functools.partial(default_config, arms=2),
               "turn a two-armed (T) valve counter-clockwise"),
    "valve3": (Valve, functools.partial(default_config, arms=3),
               "turn a three-armed valve counter-clockwise"),
    # unseen tasks (learned with a frozen synergy decoder)
    "valve_cylinder": (Valve, functools.partial(default_config, shape="wheel"),
                       "turn a round wheel valve counter-clockwise"),
    "valve_cw": (Valve, functools.partial(default_config, arms=3, direction=-1.0, success_turn=1.2),
                 "turn the three-armed valve clockwise"),
}
