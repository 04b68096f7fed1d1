"""Fault injection: a kill at any instant (inside every save too), damaged and truncated
checkpoints, a full disk, read-only folders, bad input of every kind. A run must come out
of each recoverable, with the same logs as an unbroken run, and say what happened in one
line; refused input leaves nothing behind.

The runs are the toy task's (tests/fault_worker.py: TOY), a few seconds each; kills and full
disks that need a process of their own run tests/fault_worker.py.
"""

import contextlib
import itertools
import json
import math
import os
import pathlib
import random
import select
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from discosyn_jax import tasks
import discosyn_jax.tasks.registry
from discosyn import cli
from discosyn_jax import atomic
from discosyn_jax import config as config_lib
from discosyn_jax.run import checkpoints, layout, logs, reading
from discosyn_jax.training import loop
from discosyn_jax.training.trainer import Trainer
from discosyn_jax.viz import videos
from discosyn_jax.experiments import report_runs
from tests.fault_worker import SAVES_KEEP, TOY, small_state, toy_envs
from tests.helpers import tensorboard_scalars

REPO = pathlib.Path(__file__).resolve().parents[1]
TIMING = {"wall_s", "env_steps_per_s"}  # the only columns in which two runs may differ


def toy_trainer(config=TOY) -> Trainer:
  return Trainer(config, envs=toy_envs(config))


def quiet(*_):
  pass


_WORKERS = []  # the worker processes a test started: none outlives it (_no_worker_left)


def worker(*args, env=None, **popen):
  proc = subprocess.Popen([sys.executable, "-u", "-m", "tests.fault_worker", *map(str, args)],
                          cwd=REPO, env={**os.environ, **(env or {})}, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, **popen)
  _WORKERS.append(proc)
  return proc


@pytest.fixture(autouse=True)
def _no_worker_left():
  yield
  while _WORKERS:
    proc = _WORKERS.pop()
    if proc.poll() is None:  # a test that failed before it ended its worker
      proc.kill()
      proc.communicate()


def good(run_dir) -> list[int]:
  """Steps of the checkpoints a reader of `run_dir` sees, newest first. Each must pass its
  manifest and hold its own step's values: a kill may hide a checkpoint, never damage one."""
  steps = []
  for path in checkpoints.candidates(run_dir):
    step = checkpoints.verify(path)
    restored = jax.device_get(checkpoints.restore(path, small_state(0)))
    jax.tree.map(np.testing.assert_array_equal, restored, jax.device_get(small_state(step)))
    steps.append(step)
  return steps


def leftovers(run_dir) -> list[str]:
  return sorted(p.name for p in pathlib.Path(run_dir).rglob("*")
                if p.name.endswith((".new", ".old", ".trash")) or ".orbax-checkpoint-tmp" in p.name)


def one_error_line(capsys_or_text, *fragments) -> str:
  err = capsys_or_text if isinstance(capsys_or_text, str) else capsys_or_text.readouterr().err
  lines = err.strip().splitlines()
  assert len(lines) == 1 and lines[0].startswith("discosyn: error:"), err
  for fragment in fragments:
    assert fragment in lines[0], (fragment, lines[0])
  return lines[0]


# -- kills -------------------------------------------------------------------

class Killed(BaseException):
  """A SIGKILL at that instant: the saver stops where it is (no `except Exception` of the
  code under test catches a BaseException, so nothing tidies up)."""


@contextlib.contextmanager
def killed_at(instant: int):
  """Raise Killed at the `instant`-th rename, replace or removal of an existing folder in
  the main thread: the instants between which a save changes what is on disk (orbax's
  writer threads are left to the real kills below)."""
  seen = itertools.count(1)

  def wrap(fn):
    def call(path, *args, **kwargs):
      if (threading.current_thread() is threading.main_thread() and os.path.exists(path)
          and next(seen) == instant):
        raise Killed
      return fn(path, *args, **kwargs)
    return call

  with pytest.MonkeyPatch.context() as patch:
    for module, name in ((os, "rename"), (os, "replace"), (shutil, "rmtree")):
      patch.setattr(module, name, wrap(getattr(module, name)))
    yield


@pytest.fixture(scope="module")
def saved_run(tmp_path_factory):
  """Periodic checkpoints at steps 1 and 2 (two kept) and final/ at step 2."""
  run_dir = tmp_path_factory.mktemp("saved") / "run"
  for step in (1, 2):
    checkpoints.save(run_dir, small_state(step), keep=2)
  checkpoints.save(run_dir, small_state(2), keep=2, final=True)
  return run_dir


def test_a_kill_at_any_instant_of_a_save_leaves_every_good_checkpoint(saved_run, tmp_path):
  swaps_cut = 0  # kills between the renames that swap final/: only final.old held it then
  for instant in itertools.count(1):
    run_dir = tmp_path / str(instant)
    shutil.copytree(saved_run, run_dir)
    try:
      with killed_at(instant):  # a periodic save that prunes step 1, then final/ replaced
        checkpoints.save(run_dir, small_state(3), keep=2)
        checkpoints.save(run_dir, small_state(3), keep=2, final=True)
      finished = True
    except Killed:
      finished = False
    seen = good(run_dir)
    assert len(seen) >= 3 and seen[0] >= 2, (instant, seen)  # before the saves: 1, 2, final 2
    swaps_cut += not (run_dir / "final").exists()
    checkpoints.tidy(run_dir)  # what the next writer does first: the readers' view stays
    assert good_checkpoints_of(run_dir) == seen and leftovers(run_dir) == [], instant
    if finished:
      assert seen == [3, 3, 2]  # final 3, periodic 3 and 2
      break
  assert instant > 5 and swaps_cut == 1


def _line(proc, timeout: float = 180.0) -> str:
  """The worker's next line on stdout; a worker that gives none in `timeout` seconds, or
  says something else than a step or "ready", is killed and the test fails with its stderr
  (never a hang: the worker saves forever)."""
  ready, _, _ = select.select([proc.stdout], [], [], timeout)
  line = proc.stdout.readline().strip() if ready else None
  if line is None or not (line == "ready" or line.isdigit()):
    proc.kill()
    _, err = proc.communicate()
    pytest.fail(f"the saving worker said {line!r} (None: nothing in {timeout:.0f} s); "
                f"stderr: {err[-2000:]}")
  return line


def test_kills_at_random_instants_never_cost_a_good_checkpoint(tmp_path):
  """Real SIGKILLs, wherever they land: in orbax's writer threads, between renames, in a
  prune. Each worker continues from the newest good checkpoint the last one left."""
  run_dir = tmp_path / "run"
  seed = random.randrange(2**32)
  rng = random.Random(seed)
  saved, count = 0, 0
  for _ in range(3):
    proc = worker("saves", run_dir)
    assert _line(proc) == "ready"
    saved = max(saved, int(_line(proc)))  # the first save, then at random
    time.sleep(rng.uniform(0.0, 1.0))
    proc.kill()
    out, err = proc.communicate()
    saved = max([saved, *map(int, out.split())])
    seen = good(run_dir)
    assert seen and seen[0] >= saved, (seed, saved, seen, err)
    # never fewer good checkpoints than before, up to the newest SAVES_KEEP and final/: a
    # kill between a save and its prune leaves one more, which the next save prunes
    assert len(seen) >= min(count, SAVES_KEEP + 1), (seed, count, seen)
    count = len(seen)
  assert saved >= 3, seed


# -- damage --------------------------------------------------------------------

def _largest_file(folder: pathlib.Path) -> pathlib.Path:
  files = [p for p in folder.rglob("*") if p.is_file() and p.name != checkpoints.MANIFEST]
  return max(files, key=lambda p: p.stat().st_size)


def _damage(folder: pathlib.Path, how: str) -> str:
  """Damage a checkpoint as a bad disk or a killed copy would; return the file it names."""
  if how == "manifest":
    (folder / checkpoints.MANIFEST).write_text('{"step": 2, "files": {"_MET')
    return checkpoints.MANIFEST
  data = _largest_file(folder)
  if how == "garbage":  # same size, different bytes: only a checksum sees it
    blob = bytearray(data.read_bytes())
    blob[len(blob) // 2: len(blob) // 2 + 8] = b"garbage!"
    data.write_bytes(bytes(blob))
  elif how == "truncated":
    data.write_bytes(data.read_bytes()[: data.stat().st_size // 2])
  else:
    data.unlink()
  return str(data.relative_to(folder))


@pytest.mark.parametrize("how", ["garbage", "truncated", "missing", "manifest"])
def test_a_damaged_checkpoint_is_named_once_and_the_previous_good_one_used(saved_run, tmp_path,
                                                                           capsys, how):
  run_dir = tmp_path / "run"
  shutil.copytree(saved_run, run_dir)
  name = _damage(run_dir / "final", how)
  with pytest.raises(checkpoints.Damaged, match=f"checkpoint {run_dir / 'final'} is damaged: .*"):
    checkpoints.verify(run_dir / "final")
  capsys.readouterr()
  assert checkpoints.latest(run_dir) == run_dir / "checkpoints" / "2"
  (line,) = capsys.readouterr().err.splitlines()
  assert line.startswith(f"discosyn: warning: checkpoint {run_dir / 'final'} is damaged")
  assert name in line and line.endswith("skipping it")
  # two damaged: the oldest good one
  _damage(run_dir / "checkpoints" / "2", how)
  assert checkpoints.latest(run_dir, warn=quiet) == run_dir / "checkpoints" / "1"
  _damage(run_dir / "checkpoints" / "1", how)
  assert checkpoints.latest(run_dir, warn=quiet) is None


def test_a_checkpoint_without_its_manifest_or_with_files_it_does_not_list_is_damaged(saved_run,
                                                                                      tmp_path):
  run_dir = tmp_path / "run"
  shutil.copytree(saved_run, run_dir)
  (run_dir / "final" / checkpoints.MANIFEST).unlink()  # no longer a way to skip the checks
  (run_dir / "checkpoints" / "2" / "extra").write_bytes(b"never checked")
  warnings = []
  assert checkpoints.latest(run_dir, warn=warnings.append) == run_dir / "checkpoints" / "1"
  assert warnings == [
      f"checkpoint {run_dir / 'final'} is damaged: it has no manifest.json (only checkpoints "
      f"written before {checkpoints.MANIFESTS_SINCE} may lack one); skipping it",
      f"checkpoint {run_dir / 'checkpoints' / '2'} is damaged: extra is not in its "
      f"manifest.json; skipping it"]


def test_a_checkpoint_of_the_release_before_manifests_is_still_read(tmp_path):
  """As that release wrote it: orbax's CheckpointManager layout (the item in default/), no
  manifest, committed before manifests came in."""
  import orbax.checkpoint as ocp

  item = tmp_path / "run" / "checkpoints" / "3" / "default"
  with ocp.StandardCheckpointer() as checkpointer:
    checkpointer.save(item, checkpoints._arrays(small_state(3)), custom_metadata={"step": 3})
    checkpointer.wait_until_finished()
  meta = json.loads((item / "_CHECKPOINT_METADATA").read_text())
  meta["commit_timestamp_nsecs"] = checkpoints.MANIFESTS_SINCE_NS - 86400 * 10**9
  (item / "_CHECKPOINT_METADATA").write_text(json.dumps(meta))
  assert good(tmp_path / "run") == [3]


# -- runs: kills, damage and full disks in the middle of training ------------------

def run_logs(run_dir: pathlib.Path) -> dict:
  """What a run logged, but for timings: JSONL rows and TensorBoard scalars."""
  strip = lambda rows: [{k: v for k, v in r.items() if k not in TIMING} for r in rows]
  return {"metrics": strip(logs.read_jsonl(run_dir / layout.METRICS_FILE)),
          "eval": strip(logs.read_jsonl(run_dir / layout.EVAL_FILE)),
          "tb": {tag: values for tag, values in tensorboard_scalars(run_dir / layout.TENSORBOARD_DIR).items()
                 if tag.split("/")[-1] not in TIMING}}


@pytest.fixture(scope="module")
def unbroken(tmp_path_factory):
  run_dir = tmp_path_factory.mktemp("runs") / "unbroken"
  result = loop.train(toy_trainer(), run_dir, progress=False, log=quiet)
  return run_dir, result


@pytest.fixture
def toy_tasks(monkeypatch):
  """The CLI's runs on the toy task, as tests/fault_worker.py runs them."""
  from discosyn_jax.experiments import presets

  monkeypatch.setattr(tasks.registry, "make_envs", toy_envs)
  monkeypatch.setattr(presets, "preset", lambda name: TOY)


def test_a_run_killed_inside_a_save_and_mid_line_resumes_to_the_unbroken_runs_logs(
    unbroken, tmp_path, capfd):
  straight_dir, straight = unbroken
  run_dir = tmp_path / "run"
  swap_in = atomic.swap_in

  def killed_before_swapping_in_checkpoint_4(new, target):
    if target.name == "4":
      raise Killed
    swap_in(new, target)

  with pytest.MonkeyPatch.context() as patch:
    patch.setattr(atomic, "swap_in", killed_before_swapping_in_checkpoint_4)
    with pytest.raises(Killed):
      loop.train(toy_trainer(), run_dir, progress=False, log=quiet)
  with open(run_dir / layout.METRICS_FILE, "a") as f:  # and a line the kill cut short
    f.write('{"step": 5, "loss": 0.2')
  assert json.loads((run_dir / layout.EVAL_FILE).read_text().splitlines()[-1])["step"] == 4
  resumed = loop.train(toy_trainer(), run_dir, resume=True, progress=False,
                       log=print)
  out, err = capfd.readouterr()
  assert f"resumed from {run_dir / 'checkpoints' / '2'} at step 2" in out
  assert "absl" not in err and "NaN" not in err and "Traceback" not in err, err
  assert run_logs(run_dir) == run_logs(straight_dir)
  jax.tree.map(np.testing.assert_array_equal, jax.device_get(straight["state"]),
               jax.device_get(resumed["state"]))
  assert sorted(p.name for p in (run_dir / "checkpoints").iterdir()) == ["4", "6"]


def test_a_run_killed_at_a_random_instant_resumes_to_the_unbroken_runs_logs(unbroken, tmp_path):
  straight_dir, _ = unbroken
  run_dir = tmp_path / "run"
  seed = random.randrange(2**32)
  proc = worker("train", "--out", run_dir, "--no-progress")
  for line in proc.stdout:  # the kill lands after compiling: while training, saving, logging
    if line.startswith("train step compiled"):
      break
  else:
    pytest.fail(proc.stderr.read())
  time.sleep(random.Random(seed).uniform(0.0, 2.0))
  proc.kill()
  proc.communicate()
  loop.train(toy_trainer(), run_dir, resume=True, progress=False, log=quiet)
  assert run_logs(run_dir) == run_logs(straight_dir), seed


def test_a_damaged_checkpoint_is_removed_on_resume_and_eval_falls_back(unbroken, tmp_path,
                                                                       toy_tasks, capsys):
  straight_dir, straight = unbroken
  run_dir = tmp_path / "run"
  shutil.copytree(straight_dir, run_dir)
  _damage(run_dir / "final", "garbage")
  assert cli.main(["eval", str(run_dir)]) == 0  # from checkpoints/6: the same state
  out, err = capsys.readouterr()
  (warning,) = err.splitlines()
  assert str(run_dir / "final") in warning and warning.endswith("skipped it")
  r = straight["results"]["valve1"]
  assert [l.split() for l in out.splitlines() if l.startswith("valve1 ")] == [
      ["valve1", f"{r['success']:.1%}", f"{r['return']:.2f}"]]
  _damage(run_dir / "checkpoints" / "6", "truncated")
  assert cli.main(["train", "--out", str(run_dir), "--resume", "--no-progress"]) == 0
  out, err = capsys.readouterr()
  assert len(err.splitlines()) == 2 and all(l.endswith("removed it") for l in err.splitlines())
  assert f"resumed from {run_dir / 'checkpoints' / '4'} at step 4" in out
  assert good_checkpoints_of(run_dir) == [6, 6, 4] and run_logs(run_dir) == run_logs(straight_dir)


def good_checkpoints_of(run_dir) -> list[int]:
  return [checkpoints.verify(p) for p in checkpoints.candidates(run_dir)]


@pytest.fixture(scope="module")
def small_disk():
  """Whether this machine lets an unprivileged process mount a tmpfs of its own (where it
  does not, a full disk is one that reports no free space)."""
  try:
    ok = subprocess.run(["unshare", "-r", "-m", "sh", "-c", "mount -t tmpfs none /mnt"],
                        capture_output=True).returncode == 0
  except FileNotFoundError:
    ok = False
  return ok


def _run_on_small_disk(small_disk, tmp_path, args, starve_after: int, read_only: str = ""):
  """Run the worker with its run folder RUN on a disk that fills after `starve_after`
  checkpoints (or where the folder RUN/`read_only` becomes a read-only mount then); return
  (exit status, stderr, a copy of RUN as the worker left it). A worker that does not end
  within two minutes fails the test."""
  copy = tmp_path / "run"
  env = {"FAULT_STARVE_AFTER": str(starve_after)}
  command = [sys.executable, "-u", "-m", "tests.fault_worker", *args]
  if small_disk:
    disk = tmp_path / "disk"
    disk.mkdir()
    env["FAULT_FILL"] = str(disk)
    if read_only:
      env["FAULT_READ_ONLY"] = str(disk / "run" / read_only)
    script = ('mount -t tmpfs -o size=4m none "$DISK" && "$@"; status=$?; rm -f "$DISK/ballast"; '
              'cp -a "$DISK/run" "$COPY"; exit $status')
    command = ["unshare", "-r", "-m", "sh", "-c", script, "sh",
               *[str(a).replace("RUN", str(disk / "run")) for a in command]]
    env.update(DISK=str(disk), COPY=str(copy))
  else:
    command = [str(a).replace("RUN", str(copy)) for a in command]
  # a session of its own: a worker that hangs is killed with the shell that started it
  proc = subprocess.Popen(command, cwd=REPO, env={**os.environ, **env}, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
  try:
    _, err = proc.communicate(timeout=120)
  except subprocess.TimeoutExpired:
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    pytest.fail("the worker did not end within 120 s")
  return proc.returncode, err, copy


def test_a_full_disk_fails_a_save_in_one_line_and_keeps_the_checkpoints_before(small_disk, tmp_path):
  status, err, run_dir = _run_on_small_disk(small_disk, tmp_path, ["saves", "RUN"], starve_after=4)
  # saves: 1, 2, final 2, 3; the disk full, the save of 4 fails
  assert status == 2 and len(err.strip().splitlines()) == 1, err
  assert "could not write checkpoint" in err and str(pathlib.Path("checkpoints") / "4") in err
  assert "No space left on device" in err
  assert good_checkpoints_of(run_dir) == [3, 2, 2] and leftovers(run_dir) == []


def test_a_full_disk_mid_run_stops_it_in_one_line_naming_the_last_good_checkpoint(small_disk, tmp_path):
  status, err, run_dir = _run_on_small_disk(
      small_disk, tmp_path, ["train", "--out", "RUN", "--no-progress"], starve_after=1)
  line = one_error_line(err, "training stopped at step ", ": could not write",
                        "the last good checkpoint is ")
  assert line.endswith(str(pathlib.Path("run", "checkpoints", "2")))
  assert "No space left on device" in line
  assert status == 2 and good_checkpoints_of(run_dir) == [2]


# -- one writer, Ctrl-C and SIGTERM, --force -------------------------------------------

def _wait_for(condition, proc, timeout: float = 120.0) -> None:
  """Wait until condition() holds while `proc` runs; fail with its stderr when it ends or
  the time is up (never a hang)."""
  end = time.monotonic() + timeout
  while not condition():
    if proc.poll() is not None or time.monotonic() > end:
      proc.kill()
      _, err = proc.communicate()
      pytest.fail(f"the worker ended or took over {timeout:.0f} s; stderr: {err[-2000:]}")
    time.sleep(0.05)


def _ended(proc, timeout: float = 60.0) -> tuple[int, str]:
  """(exit status, stderr) of a worker that must end by itself within `timeout` seconds."""
  try:
    _, err = proc.communicate(timeout=timeout)
  except subprocess.TimeoutExpired:
    proc.kill()
    _, err = proc.communicate()
    pytest.fail(f"the worker did not end in {timeout:.0f} s; stderr: {err[-2000:]}")
  return proc.returncode, err


def _long_run(run_dir, *flags, env=None):
  """A worker training the toy task in `run_dir` for far longer than any test waits."""
  return worker("train", "--out", run_dir, "--no-progress", "--steps", "100000", *flags, env=env)


def _resumes_from(line: str, run_dir) -> int:
  """The step of the checkpoint that a stopped run's line says it resumes from: one of
  `run_dir`'s, whole; the run's lock is gone."""
  checkpoint = pathlib.Path(line.split("; it resumes from ")[1].split(": ")[0])
  assert checkpoint.parent.parent == run_dir
  assert not (run_dir / layout.LOCK).exists()
  return checkpoints.verify(checkpoint)


def _periodic_steps(run_dir) -> list[int]:
  folder = run_dir / "checkpoints"
  return [int(p.name) for p in folder.glob("*") if p.name.isdigit()] if folder.is_dir() else []


def _snapshot(folder) -> dict[str, bytes]:
  return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(pathlib.Path(folder).rglob("*"))
          if p.is_file()}


def test_a_run_has_one_writer_readers_see_a_consistent_checkpoint_and_a_dead_writer_is_replaced(
    tmp_path, capsys, toy_tasks):
  run_dir = tmp_path / "run"
  # a checkpoint every step, one kept: the checkpoints rotate all the time
  proc = _long_run(run_dir, "--checkpoint-every", "1", "--eval-every", "0")
  _wait_for(lambda: checkpoints.candidates(run_dir), proc)
  holder = f"{run_dir} is being written by process {proc.pid} on {socket.gethostname()}, started "
  before = {"config.json": (run_dir / "config.json").read_bytes()}
  for flags in (["--resume"], ["--force"], []):  # a second writer, whatever it asks
    assert cli.main(["train", "--out", str(run_dir), *flags]) == 2
    one_error_line(capsys, holder)
  assert (run_dir / "config.json").read_bytes() == before["config.json"]
  for _ in range(40):  # readers: never a damaged or vanished checkpoint, and one line
    warnings = []
    reading.newest(run_dir, checkpoints.verify, warn=warnings.append)
    assert len(warnings) == 1 and warnings[0].startswith(holder), warnings
  assert cli.main(["eval", str(run_dir)]) == 0
  (line,) = capsys.readouterr().err.splitlines()
  assert line.startswith(f"discosyn: warning: {holder}") and ": read its checkpoint " in line
  assert not report_runs.read(run_dir).finished
  (line,) = capsys.readouterr().err.splitlines()
  assert line.startswith(f"discosyn: warning: {holder}") and "read its logs as they are now" in line
  proc.kill()  # no chance to release the lock
  _ended(proc)
  steps = [row["step"] for row in logs.read_jsonl(run_dir / layout.METRICS_FILE)]
  assert steps == list(range(1, len(steps) + 1))  # one writer: no interleaved steps
  resumed_at = good_checkpoints_of(run_dir)[0]
  assert cli.main(["train", "--out", str(run_dir), "--resume", "--steps", str(resumed_at + 1),
                   "--no-progress"]) == 0
  err = capsys.readouterr().err.splitlines()
  assert err == [f"discosyn: warning: {run_dir} was left by process {proc.pid} on "
                 f"{socket.gethostname()}, started {err[0].split(', started ')[1]}"]
  assert "which has ended without finishing; this process takes it over" in err[0]
  assert not (run_dir / layout.LOCK).exists()


@pytest.mark.parametrize("signum, status, name", [(signal.SIGINT, 130, "Ctrl-C"),
                                                  (signal.SIGTERM, 143, "SIGTERM")])
def test_ctrl_c_and_sigterm_end_a_run_in_one_line_that_says_where_it_resumes(tmp_path, signum,
                                                                             status, name):
  run_dir = tmp_path / "run"
  proc = _long_run(run_dir)
  _wait_for(lambda: max(_periodic_steps(run_dir), default=0) >= 4, proc)
  proc.send_signal(signum)
  code, err = _ended(proc)
  line = err.strip()
  assert code == status and len(err.strip().splitlines()) == 1, err
  assert line.startswith(f"discosyn: stopped by {name}: training stopped at step "), line
  assert line.endswith(f": discosyn train --out {run_dir} --resume")
  assert _resumes_from(line, run_dir) >= 4


@pytest.mark.parametrize("signum, name", [(signal.SIGINT, "KeyboardInterrupt"),
                                          (signal.SIGTERM, "Terminated")])
def test_a_script_calling_the_training_loop_is_stopped_as_cleanly_as_the_command(tmp_path, signum,
                                                                                 name):
  """No CLI: a script's own loop.train. SIGTERM (which would otherwise kill it on the spot,
  lock and all) and Ctrl-C raise their stop, which names where the run resumes."""
  run_dir = tmp_path / "run"
  proc = worker("library", run_dir)
  _wait_for(lambda: max(_periodic_steps(run_dir), default=0) >= 4, proc)
  proc.send_signal(signum)
  out, err = proc.communicate(timeout=60)
  assert proc.returncode == 1, err
  line = out.strip().splitlines()[-1]
  assert line.startswith(f"{name}: training stopped at step "), line
  assert _resumes_from(line, run_dir) >= 4


def test_ctrl_c_before_the_first_checkpoint_of_a_new_run_leaves_nothing(tmp_path):
  run_dir = tmp_path / "deep" / "run"
  proc = _long_run(run_dir, "--checkpoint-every", "100000")
  _wait_for(lambda: (run_dir / layout.METRICS_FILE).is_file(), proc)
  proc.send_signal(signal.SIGINT)
  code, err = _ended(proc)
  assert code == 130 and len(err.strip().splitlines()) == 1, err
  assert err.strip().endswith("the new run made no checkpoint and was removed")
  assert list(tmp_path.iterdir()) == []


def test_a_stop_where_python_drops_the_exception_still_stops_the_run_at_its_next_step(tmp_path):
  """The signal lands in a finalizer (as in a garbage-collector callback, or a weakref's):
  Python drops the KeyboardInterrupt raised there, and the run would go on, deaf to a
  second Ctrl-C (tests/fault_worker.py: FAULT_STOP_IN_FINALIZER)."""
  run_dir = tmp_path / "run"
  proc = _long_run(run_dir, env={"FAULT_STOP_IN_FINALIZER": "1"})
  try:
    out, err = proc.communicate(timeout=120)
  except subprocess.TimeoutExpired:
    proc.kill()
    pytest.fail(f"the run went on after the stop; its output: {proc.communicate()[0][-2000:]}")
  assert "SIGINT sent inside a finalizer" in out
  assert "the wait inside a finalizer ran to its end" not in out  # raised where it landed
  code = proc.returncode
  assert code == 130 and len(err.strip().splitlines()) == 1, err
  line = err.strip()
  assert line.startswith("discosyn: stopped by Ctrl-C: training stopped at step "), line
  assert _resumes_from(line, run_dir) >= 2


@pytest.mark.parametrize("signals, status, name", [("SIGINT", 130, "Ctrl-C"),
                                                   ("SIGINT,SIGINT", 130, "Ctrl-C"),
                                                   ("SIGTERM,SIGINT", 143, "SIGTERM")])
def test_a_stop_inside_the_physics_callback_even_pressed_twice_ends_in_one_line(tmp_path, signals,
                                                                               status, name):
  """The signal lands inside the native backend's host callback, run by the main thread
  inside the jitted train step (tests/fault_worker.py: FAULT_STOP_IN_PHYSICS); a second one
  lands while the stopped run puts its folder right."""
  run_dir = tmp_path / "run"
  proc = _long_run(run_dir, env={"FAULT_STOP_IN_PHYSICS": signals})
  out, err = proc.communicate(timeout=120)
  code = proc.returncode
  assert "sent inside the physics callback" in out
  assert "the wait inside the physics callback ran to its end" not in out  # taken where it landed
  if "," in signals:  # the second signal was sent, and the clean-up went on through it
    assert "the wait while the stopped run puts its folder right ran to its end" in out
  assert code == status and len(err.strip().splitlines()) == 1, err
  line = err.strip()
  assert line.startswith(f"discosyn: stopped by {name}: training stopped at step "), line
  assert line.endswith(f": discosyn train --out {run_dir} --resume"), line
  resumed_at = _resumes_from(line, run_dir)
  assert resumed_at >= 2
  if signals == "SIGINT":  # and the run goes on from there
    end = resumed_at + 2
    resumed = worker("train", "--out", run_dir, "--resume", "--steps", end, "--no-progress",
                     env={"FAULT_PHYSICS": "1"})
    code, err = _ended(resumed, timeout=120.0)  # a whole start: compile and all
    assert code == 0, err
    steps = [row["step"] for row in logs.read_jsonl(run_dir / layout.METRICS_FILE)]
    assert steps == list(range(1, end + 1))


@pytest.mark.parametrize("variable, value, fragment", [
    ("JAX_PLATFORMS", "bogus", "environment variable JAX_PLATFORMS='bogus': Unable to initialize "
                               "backend 'bogus'"),
    ("XLA_FLAGS", "--garbage_flag", "environment variable XLA_FLAGS holds a flag XLA does not "
                                    "know: --garbage_flag"),
    ("DISCOSYN_MJX_IMPL", "cuda", "environment variable DISCOSYN_MJX_IMPL: unknown MJX "
                                  "implementation 'cuda'; known: jax, warp"),
])
def test_a_bad_jax_environment_is_one_line_before_the_run_folder(tmp_path, variable, value,
                                                                 fragment):
  env = {**os.environ, variable: value}
  if variable == "XLA_FLAGS":
    env[variable] = f"{os.environ.get('XLA_FLAGS', '')} {value}"
  proc = subprocess.run([sys.executable, "-m", "discosyn", "train", "--tasks", "valve1",
                         "--out", str(tmp_path / "run")], cwd=REPO, env=env, text=True,
                        capture_output=True, timeout=120)
  assert proc.returncode == 2, proc.stderr
  one_error_line(proc.stderr, fragment)
  assert list(tmp_path.iterdir()) == []


def test_resume_and_force_together_are_refused(tmp_path, capsys, toy_tasks):
  assert cli.main(["train", "--out", str(tmp_path / "run"), "--resume", "--force"]) == 2
  one_error_line(capsys, "--resume continues the run in --out and --force replaces it")
  assert list(tmp_path.iterdir()) == []


def test_a_bad_scene_picture_step_leaves_no_folder(tmp_path, capsys):
  assert cli.main(["render-scenes", "valve3", "--step", "-1", "--out", str(tmp_path / "sc")]) == 2
  one_error_line(capsys, "--step must be at least 0, not -1")
  assert list(tmp_path.iterdir()) == []


def test_force_refuses_a_folder_that_is_not_a_run(tmp_path, capsys, toy_tasks):
  folder = tmp_path / "mine"
  folder.mkdir()
  (folder / "config.json").write_text("{}")  # anyone's config.json, beside a user's files
  (folder / "notes.txt").write_text("mine")
  before = _snapshot(folder)
  assert cli.main(["train", "--out", str(folder), "--force"]) == 2
  one_error_line(capsys, f"{folder} holds a config.json but no run of discosyn",
                 "--force replaces only a run")
  assert _snapshot(folder) == before


def test_force_keeps_the_old_run_whole_until_the_new_one_has_a_checkpoint(unbroken, tmp_path,
                                                                          capsys, toy_tasks):
  run_dir = tmp_path / "run"
  shutil.copytree(unbroken[0], run_dir)
  (run_dir / "videos").mkdir()  # what a user added to the run, e.g. `discosyn render`
  (run_dir / "videos" / "valve1.mp4").write_bytes(b"a video")
  old = _snapshot(run_dir)
  # Ctrl-C before the new run's first checkpoint: the process puts the old run back
  proc = _long_run(run_dir, "--force", "--checkpoint-every", "100000")
  _wait_for(lambda: (run_dir / layout.METRICS_FILE).is_file()
            and (run_dir / layout.ASIDE).is_dir(), proc)
  proc.send_signal(signal.SIGINT)
  code, err = _ended(proc)
  assert code == 130 and err.strip().endswith("the run it was to replace is back as it was"), err
  assert _snapshot(run_dir) == old
  # a kill there: the next writer puts it back
  proc = _long_run(run_dir, "--force", "--checkpoint-every", "100000")
  _wait_for(lambda: (run_dir / layout.METRICS_FILE).is_file()
            and (run_dir / layout.ASIDE).is_dir(), proc)
  proc.kill()
  _ended(proc)
  assert _snapshot(run_dir / layout.ASIDE) == old
  assert cli.main(["train", "--out", str(run_dir), "--resume", "--no-progress"]) == 0
  err = capsys.readouterr().err
  assert f"the run in {run_dir} that --force was replacing is back" in err
  assert (run_dir / "videos" / "valve1.mp4").read_bytes() == b"a video"
  assert run_logs(run_dir) == run_logs(unbroken[0])
  # a --force that reaches its first checkpoint replaces the run, the user's files too
  assert cli.main(["train", "--out", str(run_dir), "--force", "--no-progress", "--seed", "3"]) == 0
  assert sorted(p.name for p in run_dir.iterdir()) == sorted(
      ["checkpoints", "closing.json", "config.json", "eval.jsonl", "final", "metrics.jsonl", "plots",
       "tb"])
  assert json.loads((run_dir / "config.json").read_text())["seed"] == 3


# -- read-only folders ---------------------------------------------------------------

@pytest.fixture
def read_only(tmp_path):
  if os.geteuid() == 0:
    pytest.skip("root writes into read-only folders")
  folders = []

  def make(path):
    for p in (path, *[q for q in path.rglob("*") if q.is_dir()]):
      p.chmod(0o555)
      folders.append(p)
    return path

  yield make
  for p in folders:
    p.chmod(0o755)


def test_a_read_only_run_is_evaluated_but_not_resumed(unbroken, tmp_path, read_only, toy_tasks,
                                                      capsys):
  run_dir = tmp_path / "run"
  shutil.copytree(unbroken[0], run_dir)
  read_only(run_dir)
  before = sorted(p.name for p in run_dir.rglob("*"))
  assert cli.main(["eval", str(run_dir)]) == 0
  capsys.readouterr()
  assert cli.main(["train", "--out", str(run_dir), "--resume", "--steps", "8"]) == 2
  one_error_line(capsys, f"cannot write {run_dir}", "not writable")
  assert cli.main(["train", "--out", str(run_dir / "new")]) == 2
  one_error_line(capsys, "not writable")
  assert sorted(p.name for p in run_dir.rglob("*")) == before


def test_a_folder_made_read_only_mid_run_stops_it_in_one_line_and_the_process_ends(small_disk,
                                                                                   tmp_path):
  """A real read-only mount (a bind mount of checkpoints/, made read-only once the first
  checkpoint is written): orbax's writer threads once waited 20 minutes for a folder that
  could not be made, and the process with them."""
  if not small_disk:
    pytest.skip("this machine lets no process mount a file system of its own: no read-only "
                "mount to test with (as root, chmod does not stop writes)")
  status, err, run_dir = _run_on_small_disk(small_disk, tmp_path, ["train", "--out", "RUN",
                                                                   "--no-progress"],
                                            starve_after=1, read_only="checkpoints")
  line = one_error_line(err, "training stopped at step 4: could not write checkpoint",
                        "Read-only file system", "the last good checkpoint is ")
  assert line.endswith(str(pathlib.Path("run", "checkpoints", "2")))
  assert status == 2 and good_checkpoints_of(run_dir) == [2]


# -- bad input -------------------------------------------------------------------------

@pytest.mark.parametrize("flags, fragment", [
    (["--alpha2", "nan"], "alpha2 must be a finite number, not nan"),
    (["--alpha2", "inf"], "alpha2 must be a finite number, not inf"),
    (["--lr", "nan"], "learning_rate must be a finite number"),
    (["--lr", "-0.1"], "learning_rate must be positive"),
    (["--seed", str(2**64)], "seed must be a whole number between 0 and"),
    (["--seed", "-1"], "seed must be a whole number between 0 and"),
    (["--steps", str(2**40)], "steps must be at most"),
    (["--eval-every", "-2"], "eval_every must not be negative"),
])
def test_bad_hyper_parameters_are_refused_before_the_run_folder(tmp_path, capsys, toy_tasks, flags,
                                                                fragment):
  assert cli.main(["train", "--out", str(tmp_path / "run"), *flags]) == 2
  one_error_line(capsys, fragment)
  assert list(tmp_path.iterdir()) == []


def test_more_envs_than_memory_holds_are_refused_before_the_run_folder(tmp_path, capsys):
  out = tmp_path / "deep" / "run"
  argv = ["train", "--tasks", "valve1", "--backend", "native", "--num-envs", "10000000",
          "--out", str(out)]
  assert cli.main(argv) == 2
  one_error_line(capsys, "10000000 envs", "GiB", "lower num_envs")
  assert list(tmp_path.iterdir()) == []


def test_a_bad_environment_variable_is_named(tmp_path, capsys, monkeypatch):
  monkeypatch.setenv("DISCOSYN_NATIVE_THREADS", "abc")
  assert cli.main(["train", "--tasks", "valve1", "--backend", "native", "--out",
                   str(tmp_path / "run")]) == 2
  one_error_line(capsys, "DISCOSYN_NATIVE_THREADS", "'abc'")
  assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("field, value, fragment", [
    ("alpha2", math.nan, "alpha2 must be a finite number, not nan"),
    ("num_envs", "64", "num_envs must be a whole number, not '64'"),
    ("num_envs", 6.5, "num_envs must be a whole number"),
    ("tasks", "valve1", "tasks must be a list of strings"),
    ("normalize_observations", 1, "normalize_observations must be true or false"),
    ("policy_hidden", [8, "x"], "policy_hidden must be a list of whole numbers"),
])
def test_a_bad_config_file_is_named_with_its_field(unbroken, tmp_path, capsys, toy_tasks, field,
                                                   value, fragment):
  run_dir = tmp_path / "run"
  shutil.copytree(unbroken[0], run_dir)
  config = json.loads((run_dir / "config.json").read_text())
  (run_dir / "config.json").write_text(json.dumps({**config, field: value}))
  before = sorted(p.name for p in run_dir.rglob("*"))
  for argv in (["eval", str(run_dir)], ["train", "--out", str(run_dir), "--resume"]):
    assert cli.main(argv) == 2
    one_error_line(capsys, f"config file {run_dir / 'config.json'}", fragment)
  assert sorted(p.name for p in run_dir.rglob("*")) == before


def test_a_config_file_missing_a_field_is_named_never_filled_in(unbroken, tmp_path, capsys,
                                                               toy_tasks):
  run_dir = tmp_path / "run"
  shutil.copytree(unbroken[0], run_dir)
  config = json.loads((run_dir / "config.json").read_text())
  del config["unroll_length"]  # today's default (20) is not the run's (5)
  (run_dir / "config.json").write_text(json.dumps(config))
  before = _snapshot(run_dir)
  for argv in (["eval", str(run_dir)], ["train", "--out", str(run_dir), "--resume"]):
    assert cli.main(argv) == 2
    line = one_error_line(capsys, "missing config field(s): unroll_length")
    assert "upgrade" not in line
  assert _snapshot(run_dir) == before
  # a run of an older release: one line says how to upgrade it, and the upgrade works
  config = {k: v for k, v in config.items() if k not in config_lib.ADDED}
  (run_dir / "config.json").write_text(json.dumps({**config, "unroll_length": 5}))
  assert cli.main(["eval", str(run_dir)]) == 2
  one_error_line(capsys, "missing config field(s): ", f"discosyn upgrade {run_dir}` adds ",
                 "squash_z = false")
  # ... and a record's metrics archive of an older release is thinned to what a record keeps
  import lzma

  from discosyn_jax.run import logs
  rows = [{"step": s, "loss": 0.5, "a/reward": s / 8, "a/first_reward_t": 2 if s > 9 else 5}
          for s in range(1, 41)]  # paid from step 10 (5 control steps a rollout)
  (run_dir / "metrics.jsonl.xz").write_bytes(
      lzma.compress("".join(json.dumps(r) + "\n" for r in rows).encode()))
  assert cli.main(["upgrade", str(run_dir)]) == 0
  assert config_lib.load(run_dir / "config.json") == TOY.replace(**config_lib.ADDED)
  assert logs.read_jsonl(run_dir / "metrics.jsonl.xz") == logs.kept(rows, 5) != rows
  assert 10 in [r["step"] for r in logs.kept(rows, 5)]


@pytest.mark.parametrize("how, fragment", [
    ("empty", "is not a synergy file"),
    ("no meta", "is not a synergy file"),
    ("meta lacks a field", "its meta has no n_synergies"),
    ("no kernel", "synergies.kernel is absent there"),
    ("wrong shape", "synergies.kernel is (3, 20) there, (2, 20) for that decoder"),
])
def test_a_malformed_decoder_file_is_refused_in_one_line(tmp_path, capsys, toy_tasks, how, fragment):
  from discosyn_jax.synergies import fitting

  path = tmp_path / "decoder.npz"
  params = {"synergies": {"kernel": np.zeros((2, 20)), "bias": np.zeros(20)},
            "log_std": np.zeros(20)}
  fitting.save(path, params, TOY.to_dict())
  with np.load(path) as data:
    arrays = dict(data)
  meta = json.loads(str(arrays["meta"]))
  if how == "empty":
    path.write_bytes(b"")
  elif how == "no meta":
    np.savez(path, **{k: v for k, v in arrays.items() if k != "meta"})
  elif how == "meta lacks a field":
    np.savez(path, **{**arrays, "meta": json.dumps({k: v for k, v in meta.items()
                                                   if k != "n_synergies"})})
  elif how == "no kernel":
    np.savez(path, **{k: v for k, v in arrays.items() if k != "synergies.kernel"})
  else:
    np.savez(path, **{**arrays, "synergies.kernel": np.zeros((3, 20))})
  out = tmp_path / "run"
  assert cli.main(["train", "--out", str(out), "--decoder-from", str(path)]) == 2
  one_error_line(capsys, str(path), fragment)
  assert not out.exists()


def test_empty_names_are_refused_not_taken_for_defaults(tmp_path, capsys, monkeypatch):
  monkeypatch.chdir(tmp_path)
  assert cli.main(["train", "--preset", "", "--out", "run"]) == 2
  one_error_line(capsys, "unknown preset ''")
  assert cli.main(["train", "--out", ""]) == 2
  one_error_line(capsys, "--out is empty")
  assert cli.main(["render-scenes", "valve9", "--out", "scenes"]) == 2
  one_error_line(capsys, "valve9")
  assert list(tmp_path.iterdir()) == []


def test_the_output_folder_must_be_a_folder(tmp_path, capsys, toy_tasks):
  blocker = tmp_path / "file"
  blocker.write_text("not a folder")
  assert cli.main(["train", "--out", str(blocker)]) == 2
  one_error_line(capsys, f"{blocker} is a file")
  assert cli.main(["train", "--out", str(blocker / "run")]) == 2
  one_error_line(capsys, f"{blocker} is a file")
  assert blocker.read_text() == "not a folder" and sorted(tmp_path.iterdir()) == [blocker]


def test_task_overrides_are_checked():
  for overrides, fragment in (({"frictionloss": -1.0}, "frictionloss must not be negative"),
                              ({"damping": math.nan}, "damping must be a finite number"),
                              ({"max_rewarded_speed": 0.0}, "max_rewarded_speed must be > 0"),
                              ({"episode_length": 0}, "episode_length must be at least 1"),
                              ({"arms": "3"}, "arms must be a whole number")):
    with pytest.raises(ValueError, match=f"task 'valve1': {fragment}"):
      tasks.make("valve1", backend="native", **overrides)
  with pytest.raises(ValueError, match="task 'screw': frictionloss must not be negative"):
    tasks.make("screw", backend="native", frictionloss=-0.1)


def test_a_batch_of_actions_to_one_env_is_a_clear_error():
  env = tasks.make("valve1", backend="native")
  state = env.reset(jax.random.PRNGKey(0))
  for step in (env.step, jax.jit(env.step)):
    with pytest.raises(ValueError, match=r"shape \(20,\), not \(2, 20\).*jax.vmap"):
      step(state, jnp.zeros((2, 20)))


def test_render_flags_are_checked_before_the_rollout(tmp_path, capsys, monkeypatch):
  from tests.test_pictures_videos import TINY
  from tests.test_pictures_videos import saved_run as make_saved_run

  run_dir = tmp_path / "run"
  make_saved_run(run_dir, TINY)

  def no_rollout(*args, **kwargs):
    raise AssertionError("the rollout ran")

  monkeypatch.setattr(videos, "episode_states", no_rollout)
  before = sorted(p.name for p in run_dir.rglob("*"))
  for flags, fragment in ((["--height", "100000"], "--height must be between 1 and 480"),
                          (["--width", "0"], "--width must be between 1 and 640"),
                          (["--frame", "99999"], "--frame must be between 0 and 99"),
                          (["--frame", "-1"], "--frame must be between 0 and 99"),
                          (["--seed", str(2**64)], "--seed must be a whole number"),
                          (["--episodes", "0"], "--episodes must be at least 1")):
    assert cli.main(["render", str(run_dir), "--task", "valve1", *flags]) == 2
    one_error_line(capsys, fragment)
  assert sorted(p.name for p in run_dir.rglob("*")) == before


def test_tensorboard_takes_non_finite_values_without_warnings(tmp_path, capfd):
  with logs.TensorBoard(tmp_path) as board:
    board.write({"step": 1, "env_steps": 20, "loss": math.nan, "a/return": math.inf}, "train")
  scalars = tensorboard_scalars(tmp_path / layout.TENSORBOARD_DIR)
  assert math.isnan(scalars["train/loss"][0][1]) and scalars["a/return"] == [(20, math.inf)]
  assert capfd.readouterr().err == ""
