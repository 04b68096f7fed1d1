"""Other packages' imports as a user's script meets them: MuJoCo's MJX without the "Failed to
import warp" lines it prints on stdout wherever the optional Warp packages are absent (the
CPU path never needs them), and Brax with the JAX its trainers call (brax_compatible).

Importing this module (`import discosyn_jax` does) imports no JAX: it puts a finder on
sys.meta_path that quiets MJX's import and completes JAX for Brax's, whoever makes them
later and in whatever order (a user's script that calls Brax's PPO before any env of ours);
`import_mjx` imports MJX now. An MJX imported before the package has printed its lines
already; a Brax imported before it gets its JAX at once."""

from __future__ import annotations

import contextlib
import io
import sys

_NOISE = ("Failed to import warp", "Failed to import mujoco_warp")
_NOISY = frozenset({"mujoco.mjx", "mujoco.mjx.warp"})  # mjx imports its warp part as it loads
_BRAX = "brax"


def brax_compatible() -> None:
  """Give JAX back `jax.device_put_replicated`, removed in JAX 0.10 and still called by Brax
  0.14.2's PPO and SAC (`brax.training.agents.*.train`), where this JAX lacks it: a leading
  axis of one copy per device, which their pmap splits. A JAX that still has it keeps its own."""
  import jax

  def device_put_replicated(tree, devices):
    import jax.numpy as jnp

    return jax.tree.map(lambda x: jnp.stack([jnp.asarray(x)] * len(devices)), tree)

  if not hasattr(jax, "device_put_replicated"):
    jax.device_put_replicated = device_put_replicated


def _quietly(run):
  """Run `run()` with its stdout kept back but for the lines that are not the noise."""
  captured = io.StringIO()
  try:
    with contextlib.redirect_stdout(captured):
      return run()
  finally:
    for line in captured.getvalue().splitlines():
      if not line.startswith(_NOISE):
        print(line, file=sys.stdout)


class _QuietLoader:
  """The module's own loader, its code run with the noise kept back."""

  def __init__(self, loader):
    self._loader = loader

  def create_module(self, spec):
    return self._loader.create_module(spec)

  def exec_module(self, module):
    module.__loader__ = self._loader  # the module's own, for whoever asks it later
    if module.__name__ == _BRAX:
      self._loader.exec_module(module)
      brax_compatible()
    else:
      _quietly(lambda: self._loader.exec_module(module))

  def __getattr__(self, name):
    return getattr(self._loader, name)


class _QuietFinder:
  """sys.meta_path's finder of MJX's modules and Brax: the spec the other finders give, its
  loader wrapped."""

  @classmethod
  def find_spec(cls, name, path=None, target=None):
    if name not in _NOISY and name != _BRAX:
      return None
    for finder in sys.meta_path:
      if finder is cls or not hasattr(finder, "find_spec"):
        continue
      spec = finder.find_spec(name, path, target)
      if spec is not None:
        if spec.loader is not None and hasattr(spec.loader, "exec_module"):
          spec.loader = _QuietLoader(spec.loader)
        return spec
    return None


def install() -> None:
  if _QuietFinder not in sys.meta_path:
    sys.meta_path.insert(0, _QuietFinder)
  if _BRAX in sys.modules:  # imported before this package: its JAX already loaded
    brax_compatible()


def import_mjx() -> None:
  install()
  import mujoco.mjx  # noqa: F401


install()
