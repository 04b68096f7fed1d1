"""Training: the Trainer (init and the jitted train step on the envs it is given), the
deterministic evaluation, the device mesh, and the host loop that runs a run in its folder."""

from discosyn_jax import quiet_mjx  # noqa: F401  (first: MJX imported quietly, before brax)
