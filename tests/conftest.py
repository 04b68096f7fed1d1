import os

# Keep the native backend to one thread per test process on the 2-core CI machine, and
# import discosyn_jax (which sets XLA flags) before anything imports jax.
os.environ.setdefault("DISCOSYN_NATIVE_THREADS", "2")
import discosyn_jax  # noqa: E402,F401
