"""Run in its own process by tests/test_faults.py, to be killed or to run out of disk:

  python -u -m tests.fault_worker saves RUN_DIR
      save small states as periodic checkpoints of RUN_DIR (and as final/ every other step)
      forever, from the step after its newest good one, printing each step once saved
  python -u -m tests.fault_worker train ARGS...
      `discosyn ARGS` with the toy task (tests/toy_env.py) in place of every hand task and
      TOY in place of every preset; exits with the CLI's status

FAULT_STARVE_AFTER=N (both modes): after the N-th checkpoint this process writes, the disk
is full: a file fills the small tmpfs the run is on (FAULT_FILL names it), or else, where no
tmpfs could be mounted, the disk reports no free space to the checkpoints.
FAULT_READ_ONLY=FOLDER: instead, FOLDER becomes a read-only mount (a bind mount of itself,
in the mount namespace the test made).
"""

import os
import pathlib
import shutil
import subprocess
import sys
import types

import discosyn_jax

# before brax imports MJX: MJX prints "Failed to import warp" on stdout, which the test
# reads line by line ("ready", then each saved step)
discosyn_jax.setup_jax()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from flax import struct  # noqa: E402

from discosyn_jax import checkpoints  # noqa: E402
from discosyn_jax.config import TrainConfig  # noqa: E402
from tests.toy_env import ReachAction  # noqa: E402

TOY = TrainConfig(tasks=("valve1",), n_synergies=2, policy_hidden=(8,), value_hidden=(8,),
                  discriminator_hidden=(8,), num_envs=4, unroll_length=5, num_minibatches=2,
                  update_epochs=1, steps=6, eval_every=1, eval_envs=2, checkpoint_every=2,
                  keep_checkpoints=2, backend="native")


def toy_envs(config):
  return [ReachAction(0.3 + 0.1 * n, episode_length=5) for n, _ in enumerate(config.tasks)]


@struct.dataclass
class Small:
  params: dict
  step: jax.Array


def small_state(step: int) -> Small:
  """A state whose every value says which step it belongs to."""
  return Small(params={"w": jnp.arange(12.0).reshape(3, 4) + step, "b": jnp.full((5,), step * 0.5)},
               step=jnp.asarray(step, jnp.int32))


def starve() -> None:
  read_only = os.environ.get("FAULT_READ_ONLY")
  if read_only:
    for options in (["--bind"], ["-o", "remount,bind,ro"]):
      subprocess.run(["mount", *options, read_only, read_only], check=True)
    return
  fill = os.environ.get("FAULT_FILL")
  if not fill:  # no tmpfs to fill: the disk says it is full
    shutil.disk_usage = lambda path: types.SimpleNamespace(total=2**30, used=2**30, free=0)
    return
  try:
    with open(pathlib.Path(fill) / "ballast", "wb") as f:
      while True:
        f.write(b"\0" * 65536)
        f.flush()
  except OSError:
    pass


def starve_after_saves() -> None:
  limit = int(os.environ.get("FAULT_STARVE_AFTER", "0"))
  if not limit:
    return
  save, done = checkpoints.save, []

  def counted(*args, **kwargs):
    path = save(*args, **kwargs)
    done.append(path)
    if len(done) == limit:
      starve()
    return path

  checkpoints.save = counted


def saves(run_dir: pathlib.Path) -> None:
  checkpoints.tidy(run_dir)
  newest = checkpoints.latest(run_dir)
  step = checkpoints.verify(newest) + 1 if newest else 1
  print("ready", flush=True)
  while True:
    checkpoints.save(run_dir, small_state(step), keep=2)
    if step % 2 == 0:
      checkpoints.save(run_dir, small_state(step), keep=2, final=True)
    print(step, flush=True)
    step += 1


def main() -> int:
  starve_after_saves()
  mode, *args = sys.argv[1:]
  if mode == "saves":
    try:
      saves(pathlib.Path(args[0]))
    except checkpoints.SaveFailed as err:
      print(f"save failed: {err}", file=sys.stderr)
      return 2
  import tasks.registry
  from discosyn import cli
  from experiments import presets

  tasks.registry.make_envs = toy_envs
  presets.preset = lambda name: TOY
  return cli.main(sys.argv[1:])


if __name__ == "__main__":
  from discosyn import cli

  cli.exit_with(main())  # as the `discosyn` command ends
