"""Pieces every task module uses: the hand's joint addresses (any hand: hands.py), its noisy
start pose, angles, the fast physics settings."""

from __future__ import annotations

import types

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from discosyn_jax.checks import BadInput
from discosyn_jax.env import hands

# The "fast" physics profile's settings our tasks declare (Task.fast_physics): each task's
# cheapest that stayed within the tolerances of the reference (4 ms x 10) in
# studies/physics_study.py (docs/BENCHMARKS.md, "Physics settings", 2026-12-02): 8 ms steps,
# the valves' contacts as stiff as at 4 ms (refsafe off; the screws diverge or bounce so).
EIGHT_MS = types.MappingProxyType(dict(n_substeps=5))
EIGHT_MS_STIFF = types.MappingProxyType(dict(n_substeps=5, refsafe=False))


class HandJoints:
  """The hand's qpos addresses and ranges in one compiled model (looked up on the host)."""

  def __init__(self, model: mujoco.MjModel):
    ids = hands.joint_ids(model)
    self.qpos = jnp.asarray(hands.qpos_indices(model))
    limited = model.jnt_limited[ids].astype(bool)  # a hand of one's own may leave joints unlimited
    self.lo = jnp.asarray(np.where(limited, model.jnt_range[ids, 0], -np.inf), jnp.float32)
    self.hi = jnp.asarray(np.where(limited, model.jnt_range[ids, 1], np.inf), jnp.float32)
    self.qpos0 = jnp.asarray(model.qpos0, jnp.float32)  # the whole model's reference pose
    self.nv = model.nv

  def start_qpos(self, rng: jax.Array, noise: float) -> jax.Array:
    """The model's reference qpos with the hand joints moved by uniform noise in +-`noise`."""
    delta = noise * jax.random.uniform(rng, self.qpos.shape, minval=-1, maxval=1)
    hand_q = jnp.clip(self.qpos0[self.qpos] + delta, self.lo, self.hi)
    return self.qpos0.at[self.qpos].set(hand_q)

  def zero_qvel(self) -> jax.Array:
    return jnp.zeros(self.nv, jnp.float32)


def joint_address(model: mujoco.MjModel, name: str) -> tuple[int, int]:
  """(qpos address, qvel address) of joint `name`."""
  joint = model.joint(name)
  return int(joint.qposadr[0]), int(joint.dofadr[0])


def wrap_angle(angle: jax.Array) -> jax.Array:
  """`angle` in [-pi, pi)."""
  return jnp.mod(angle + jnp.pi, 2 * jnp.pi) - jnp.pi


def capped_speed(delta: jax.Array, dt: float, cap: float) -> jax.Array:
  """Mean speed over a control step (`delta` / `dt`), clipped to +-`cap`: a rewarded speed."""
  return jnp.clip(delta / dt, -cap, cap)


def require(condition: bool, message: str) -> None:
  """A bad config value: a ValueError that says which and why."""
  if not condition:
    raise BadInput(message)


def require_hinge(config) -> None:
  """The fields of a task that turns an object on a hinge (valves, screws): its physics
  and the speed up to which turning is rewarded."""
  for name in ("damping", "frictionloss"):
    require(getattr(config, name) >= 0, f"{name} must not be negative, not {getattr(config, name)}")
  require(config.max_rewarded_speed > 0,
          f"max_rewarded_speed must be > 0 rad/s, not {config.max_rewarded_speed}")
