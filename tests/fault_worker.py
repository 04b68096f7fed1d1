"""Run in its own process by tests/test_faults.py, to be killed or to run out of disk:

  python -u -m tests.fault_worker saves RUN_DIR
      save small states as periodic checkpoints of RUN_DIR (and as final/ every other step)
      forever, from the step after its newest good one, printing each step once saved
  python -u -m tests.fault_worker train ARGS...
      `discosyn ARGS` with the toy task (tests/toy_env.py) in place of every hand task and
      TOY in place of every preset; exits with the CLI's status
  python -u -m tests.fault_worker library RUN_DIR
      a script's own call of `training.loop.train` (no CLI) on the toy task, far longer than
      any test waits; on a stop, prints the exception's class and message on stdout

FAULT_STARVE_AFTER=N (both modes): after the N-th checkpoint this process writes, the disk
is full: a file fills the small tmpfs the run is on (FAULT_FILL names it), or else, where no
tmpfs could be mounted, the disk reports no free space to the checkpoints.
FAULT_READ_ONLY=FOLDER: instead, FOLDER becomes a read-only mount (a bind mount of itself,
in the mount namespace the test made).
FAULT_PHYSICS=1 (train): the toy task steps MuJoCo through the native backend's host
callback (tests/toy_env.py: PhysicsReach).
FAULT_STOP_IN_PHYSICS=SIG[,SIG2] (train): as FAULT_PHYSICS, and in the first physics call on the
main thread after the first checkpoint the process sends itself SIG and waits inside the
callback, so the signal lands there; SIG2, if named, is sent again while the stopped run puts its folder
right (pressed twice). Stdout says where each signal was sent, and whether the waiting
callback ran to its end (a stop not taken where it landed).
FAULT_STOP_IN_FINALIZER=1 (train): after the first checkpoint, an object's finalizer
(`__del__`, run on the main thread between two train steps) sends this process SIGINT and
waits, so the signal lands there, where Python drops any exception raised.
"""

import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading
import time
import types

import discosyn_jax
from discosyn_jax.run import jax_setup  # noqa: E402

# before brax imports MJX: MJX prints "Failed to import warp" on stdout, which the test
# reads line by line ("ready", then each saved step)
jax_setup.setup_jax()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from flax import struct  # noqa: E402

from discosyn_jax.config import TrainConfig  # noqa: E402
from discosyn_jax.run import checkpoints  # noqa: E402
from tests.toy_env import ReachAction  # noqa: E402

TOY = TrainConfig(squash_z=False, decoder_init="random", tasks=("valve1",), n_synergies=2, policy_hidden=(8,), value_hidden=(8,),
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


def physics_envs(config):
  from tests.toy_env import PhysicsReach

  return [PhysicsReach(0.3 + 0.1 * n, episode_length=5) for n, _ in enumerate(config.tasks)]


def _send_and_wait(signum: int, where: str) -> None:
  print(f"{signal.Signals(signum).name} sent {where}", flush=True)
  os.kill(os.getpid(), signum)
  for _ in range(200):  # 2 s: a handler that raises ends this wait where the signal landed
    time.sleep(0.01)
  print(f"the wait {where} ran to its end", flush=True)


def count_saves() -> list:
  """The list to which every checkpoint this process saves from here on is appended."""
  saved, save = [], checkpoints.save

  def counted_save(*args, **kwargs):
    saved.append(save(*args, **kwargs))
    return saved[-1]

  checkpoints.save = counted_save
  return saved


def stop_in_physics(signals: str) -> None:
  """FAULT_STOP_IN_PHYSICS: see the module's docstring."""
  import mujoco.batch

  # XLA runs a CPU computation on the calling thread, or on its own threads when it is
  # dispatched before its inputs are ready; only the main thread takes a signal: the signal
  # is sent from a physics call on the main thread, which this makes the rule
  jax.config.update("jax_cpu_enable_async_dispatch", False)
  first, *again = [getattr(signal, name) for name in signals.split(",")]
  saved, sent = count_saves(), []
  rollout, latest = mujoco.batch.Batch.rollout, checkpoints.latest

  def stopping_rollout(self, *args, **kwargs):
    if saved and not sent and threading.current_thread() is threading.main_thread():
      sent.append(first)
      _send_and_wait(first, "inside the physics callback")
    return rollout(self, *args, **kwargs)

  def latest_pressed_again(*args, **kwargs):
    if sent and again and len(sent) == 1:
      sent.append(again[0])
      _send_and_wait(again[0], "while the stopped run puts its folder right")
    return latest(*args, **kwargs)

  mujoco.batch.Batch.rollout = stopping_rollout
  checkpoints.latest = latest_pressed_again


def stop_in_finalizer() -> None:
  """FAULT_STOP_IN_FINALIZER: see the module's docstring."""
  from discosyn_jax.run import logs

  saved, dropped, write = count_saves(), [], logs.TensorBoard.write

  class Finalized:
    def __del__(self):
      _send_and_wait(signal.SIGINT, "inside a finalizer")

  def write_dropping_one(self, row, kind):
    if saved and not dropped:
      dropped.append(True)
      Finalized()  # dropped at once: its __del__ runs here
    return write(self, row, kind)

  logs.TensorBoard.write = write_dropping_one


SAVES_KEEP = 2  # periodic checkpoints the saving worker keeps, besides final/


def saves(run_dir: pathlib.Path) -> None:
  checkpoints.tidy(run_dir)
  newest = checkpoints.latest(run_dir)
  step = checkpoints.verify(newest) + 1 if newest else 1
  print("ready", flush=True)
  while True:
    checkpoints.save(run_dir, small_state(step), keep=SAVES_KEEP)
    if step % 2 == 0:
      checkpoints.save(run_dir, small_state(step), keep=SAVES_KEEP, final=True)
    print(step, flush=True)
    step += 1


def library(run_dir: pathlib.Path) -> int:
  import dataclasses

  from discosyn_jax import assemble

  config = dataclasses.replace(TOY, steps=100000, eval_every=0)
  try:
    assemble.train(config, run_dir, progress=False, log=lambda _: None)
  except KeyboardInterrupt as err:
    print(f"{type(err).__name__}: {err}", flush=True)
    return 1
  return 0


def main() -> int:
  starve_after_saves()
  mode, *args = sys.argv[1:]
  if mode == "saves":
    try:
      saves(pathlib.Path(args[0]))
    except checkpoints.SaveFailed as err:
      print(f"save failed: {err}", file=sys.stderr)
      return 2
  from discosyn import cli
  from discosyn_jax.experiments import presets
  from discosyn_jax.tasks import registry as task_registry

  task_registry.make_envs = toy_envs
  if mode == "library":
    return library(pathlib.Path(args[0]))
  if os.environ.get("FAULT_PHYSICS") or os.environ.get("FAULT_STOP_IN_PHYSICS"):
    task_registry.make_envs = physics_envs
  if os.environ.get("FAULT_STOP_IN_PHYSICS"):
    stop_in_physics(os.environ["FAULT_STOP_IN_PHYSICS"])
  if os.environ.get("FAULT_STOP_IN_FINALIZER"):
    stop_in_finalizer()
  presets.preset = lambda name: TOY
  return cli.main(sys.argv[1:])


if __name__ == "__main__":
  from discosyn import cli

  cli.exit_with(main())  # as the `discosyn` command ends
