"""The environment's settings a run's config names: the control step, the physics backends
and the physics profiles. Plain values, no JAX, so that the config (which `discosyn --help`
reads) can import them without importing the physics."""

BACKENDS = ("auto", "native", "mjx")  # auto: native on a CPU, mjx on an accelerator
CONTROL_DT = 0.04  # s: one control step of every task
# The physics of the tasks (discosyn_jax/tasks/registry.py, physics_overrides): "reference" is 10 MuJoCo
# steps of 4 ms per control step for every task, what every run before this field ran;
# "fast" is each task's cheapest setting that stays faithful to the reference, as the task
# declares it (Task.fast_physics; docs/BENCHMARKS.md, "Physics settings"). A profile never changes once runs use it: a
# new choice gets a new name.
PHYSICS = ("fast", "reference")
