"""Many devices, one run: the env batch and the PPO minibatches split over a 1-D mesh.

The layout, in JAX's own sharding terms (a `Mesh` with one axis, "batch"):
  env states, rollouts, GAE inputs, minibatches   sharded on their env/sample axis
  parameters, optimiser state, normalisers, rng   replicated
The rollout runs under `shard_map`, so every device steps its own envs (the native
backend's host callback is called once per device with that device's envs); everything
after it is written for the whole batch and partitioned by XLA (GSPMD): the loss is a mean
over the sharded samples, so its gradient is the all-reduced (averaged) gradient, and one
device and many compute the same numbers up to the order of float sums.

Multi-host: call `initialize_distributed()` (`discosyn train --distributed`) in every
process before anything else touches JAX; the mesh then spans `jax.devices()` of all hosts.
"""

from __future__ import annotations

from typing import Sequence

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding
from jax.sharding import PartitionSpec as P

from discosyn_jax.checks import BadInput

AXIS = "batch"


def make_mesh(devices: Sequence[jax.Device] | int | None = None) -> Mesh:
  """A 1-D mesh over `devices` (a list, a count of the first devices, or all of them)."""
  every = jax.devices()
  if devices is None:
    devices = every
  elif isinstance(devices, int):
    if not 1 <= devices <= len(every):
      raise BadInput(f"--devices must be between 1 and {len(every)} here, not {devices}")
    devices = every[:devices]
  return Mesh(np.asarray(devices), (AXIS,))


def replicated(mesh: Mesh) -> NamedSharding:
  return NamedSharding(mesh, P())


def batched(mesh: Mesh, leading: int = 0) -> NamedSharding:
  """Sharded on axis `leading` (the env or sample axis), replicated on the others."""
  return NamedSharding(mesh, P(*([None] * leading), AXIS))


def mesh_for(config, devices=None) -> Mesh:
  """The mesh a training config runs on; BadInput naming the first batch size (envs per
  task, samples per minibatch) that does not split evenly over its devices."""
  mesh = make_mesh(devices)
  sizes = {"num_envs": config.num_envs,
           "minibatch_size": config.num_envs * config.unroll_length // config.num_minibatches}
  for name, size in sizes.items():
    if size % mesh.size:
      raise BadInput(f"{name} = {size} does not split over {mesh.size} devices")
  return mesh


def initialize_distributed(**kwargs) -> None:
  """Join a multi-host run: `jax.distributed.initialize` reads the coordinator, process
  count and id from `kwargs` or, on SLURM / TPU / Kubernetes clusters, from the environment
  (JAX_COORDINATOR_ADDRESS, JAX_NUM_PROCESSES, JAX_PROCESS_ID elsewhere)."""
  jax.distributed.initialize(**kwargs)
