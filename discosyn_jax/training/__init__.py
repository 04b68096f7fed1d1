"""Training: the Trainer (init and the jitted train step on the envs it is given), the
deterministic evaluation, the device mesh, and the host loop that runs a run in its folder."""

from discosyn_jax import quiet_mjx as _quiet_mjx

_quiet_mjx.import_mjx()  # before brax or MJX print their Warp notices
