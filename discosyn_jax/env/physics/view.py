"""What a task reads of the physics, whatever the backend (physics/__init__.py)."""

import jax
from flax import struct


@struct.dataclass
class PhysicsView:
  qpos: jax.Array
  qvel: jax.Array
  sensordata: jax.Array
