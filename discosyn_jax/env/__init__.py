"""The environment: a Task (a scene and pure JAX functions of a PhysicsView) on a physics
backend (MuJoCo C in a host callback, or MJX) as a Brax Env; hands, scenes, MJCF files,
scripted motions, rollouts and the training and evaluation wrappers."""

from discosyn_jax import quiet_mjx as _quiet_mjx

_quiet_mjx.import_mjx()  # before brax or MJX print their Warp notices
