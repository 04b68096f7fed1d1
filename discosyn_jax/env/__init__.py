"""The environment: a Task (a scene and pure JAX functions of a PhysicsView) on a physics
backend (MuJoCo C in a host callback, or MJX) as a Brax Env; hands, scenes, MJCF files,
scripted motions, rollouts and the training and evaluation wrappers."""

