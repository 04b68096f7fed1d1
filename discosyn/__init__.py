"""The `discosyn` command line, above the library (discosyn_jax), the tasks and the
experiments: the one place that knows all three (docs/ARCHITECTURE.md)."""
