"""Checkpoints of the whole TrainState (parameters, every optimiser state, normalisers, env
states, rng, step) with orbax, each with a manifest that lets a reader trust it.

A run keeps them in checkpoints/<step>/ (the newest `keep_checkpoints`) and final/
(layout.py names the rest of its folder).

A checkpoint is an orbax checkpoint plus manifest.json: its step, and the size and SHA-256
of every file in it. It is written whole as `NAME.new` beside the others and swapped in by
renames (atomic.py), `final/` too, so a kill at any instant leaves every checkpoint that
was complete before it. Readers verify the manifest (a missing one, or a file it does not
list, is damage too): a damaged checkpoint is skipped with one line naming it, and the
newest good one is used; of a run being written, the checkpoints that rotate away while
read are read again (read_newest).

One file over 300 lines on purpose: writing, verifying and reading share one format and one
swap protocol, which a split would spread over two files that must change together.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import logging
import math
import os
import pathlib
import re
import shutil
import signal
import sys
import threading

import jax
import orbax.checkpoint as ocp

from discosyn_jax import atomic
from discosyn_jax.checks import BadInput
from discosyn_jax.run import layout

MANIFEST = "manifest.json"
_ITEM = "default"  # the item folder of checkpoints written by orbax's CheckpointManager (older runs)
_ORBAX_TMP = ".orbax-checkpoint-tmp"  # orbax's own folder while it writes
# the release that gave every checkpoint a manifest (commit ea672cf): only a checkpoint
# committed before it may lack one
MANIFESTS_SINCE = "2026-11-29 22:33 UTC"
MANIFESTS_SINCE_NS = 1795991614 * 10**9


class Damaged(BadInput):
  """A checkpoint that cannot be read or whose files differ from its manifest."""


class SaveFailed(OSError):
  """A checkpoint could not be written (e.g. a full disk); the ones before it are intact."""


def warn(message: str) -> None:
  print(f"discosyn: warning: {message}", file=sys.stderr)


@contextlib.contextmanager
def _quiet():
  """Keep orbax's absl log lines (a metadata warning on every restore, tracebacks from its
  writer threads on a full disk) off the terminal: what fails is reported here, in one line."""
  logger = logging.getLogger("absl")
  level = logger.level
  logger.setLevel(logging.CRITICAL)
  try:
    yield
  finally:
    logger.setLevel(level)


@contextlib.contextmanager
def _signals_deferred():
  """Ctrl-C and SIGTERM wait until the block ends (they act right after it): orbax's writer
  threads, left running by a save the signal cut short, printed tracebacks at exit."""
  if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
    yield
    return
  previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
  try:
    yield
  finally:
    signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _silence_abandoned_writes() -> None:
  """After a failed save, orbax's writer threads go on failing in the background, and the
  asyncio futures it abandons log their traceback whenever they are collected, up to the
  process's exit: all of it is the one error SaveFailed reports."""
  logging.getLogger("absl").setLevel(logging.CRITICAL)
  logging.getLogger("asyncio").setLevel(logging.CRITICAL)


def _named_leaves(tree) -> list[tuple[str, object]]:
  def name(key):
    for attr in ("name", "key", "idx"):
      if hasattr(key, attr):
        return str(getattr(key, attr))
    return str(key)

  return [(".".join(name(k) for k in path), leaf)
          for path, leaf in jax.tree_util.tree_flatten_with_path(tree)[0]]


def _arrays(tree) -> dict[str, jax.Array]:
  """The state's arrays by path name. Empty arrays (e.g. the sensors of a model without
  any) and Python constants are left out: orbax cannot store the first, and the second
  come from the config."""
  return {name: leaf for name, leaf in _named_leaves(tree)
          if isinstance(leaf, jax.Array) and leaf.size > 0}


# -- writing -------------------------------------------------------------------

def _digest(path: pathlib.Path, sync: bool = False) -> str:
  sha = hashlib.sha256()
  with open(path, "rb") as f:
    for block in iter(lambda: f.read(1 << 20), b""):
      sha.update(block)
    if sync:  # the data reaches the disk before the rename that publishes it
      os.fsync(f.fileno())
  return sha.hexdigest()


def _files(folder: pathlib.Path) -> list[pathlib.Path]:
  return sorted(p for p in folder.rglob("*") if p.is_file() and p.name != MANIFEST)


def _write(folder: pathlib.Path, arrays: dict, step: int) -> None:
  # folders made in this thread: made by orbax's writer threads, a folder that cannot be
  # made (a read-only mount) left the others waiting for it for 20 minutes, and the
  # process could not exit until they gave up
  synchronous = ocp.AsyncOptions(create_directories_asynchronously=False)
  with _signals_deferred(), _quiet(), ocp.StandardCheckpointer(async_options=synchronous) as checkpointer:
    checkpointer.save(folder.resolve(), arrays, custom_metadata={"step": step})
    checkpointer.wait_until_finished()
  files = {str(p.relative_to(folder)): {"bytes": p.stat().st_size, "sha256": _digest(p, sync=True)}
           for p in _files(folder)}
  atomic.write_text(folder / MANIFEST, json.dumps({"step": step, "files": files}, indent=1))


def _check_room(folder: pathlib.Path, arrays: dict) -> None:
  """Fail before orbax starts when the disk cannot hold the checkpoint (its arrays
  uncompressed, and a MiB of metadata): orbax's writer threads, cut short by a full disk,
  go on failing in the background and print tracebacks."""
  needed = sum(a.nbytes for a in arrays.values()) + 2**20
  free = shutil.disk_usage(folder).free
  if free < needed:
    raise OSError(errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} ({free / 2**20:.1f} MiB free, "
                                f"the checkpoint needs up to {needed / 2**20:.1f} MiB)")


def _reason(err: BaseException) -> str:
  """What went wrong, in a few words: tensorstore reports an OS error as text."""
  if isinstance(err, OSError) and err.strerror:
    return err.strerror
  code = re.search(r"os_error_code='?(\d+)", str(err))
  if code:
    return os.strerror(int(code.group(1)))
  return str(err).splitlines()[0][:200] if str(err) else type(err).__name__


def _clear_leftovers(folder: pathlib.Path) -> None:
  for pattern in (f"*{_ORBAX_TMP}*", f"*{atomic.TRASH}"):
    for path in folder.glob(pattern):
      shutil.rmtree(path, ignore_errors=True)


def tidy(run_dir: pathlib.Path) -> None:
  """Finish what a kill interrupted in a run's checkpoints (the writer's job, before it
  reads or saves): unfinished writes go, an interrupted swap is completed or undone."""
  run_dir = pathlib.Path(run_dir)
  atomic.settle(run_dir / layout.FINAL)
  _clear_leftovers(run_dir)
  periodic = run_dir / layout.PERIODIC
  if periodic.is_dir():
    for name in {p.name.split(".")[0] for p in periodic.iterdir() if p.name.split(".")[0].isdigit()}:
      atomic.settle(periodic / name)
    _clear_leftovers(periodic)


def save(run_dir: pathlib.Path, state, keep: int, final: bool = False) -> pathlib.Path:
  """Write `state` as a periodic checkpoint (named by its step, the newest `keep` kept) or
  as `final`; return its folder. Raises SaveFailed, leaving the older checkpoints intact."""
  run_dir = pathlib.Path(run_dir)
  step = int(state.step)
  target = run_dir / layout.FINAL if final else run_dir / layout.PERIODIC / str(step)
  tidy(run_dir)
  new = atomic.sibling(target, atomic.NEW)
  arrays, failure = _arrays(state), None
  try:
    target.parent.mkdir(parents=True, exist_ok=True)
    _check_room(target.parent, arrays)
    _write(new, arrays, step)
  except Exception as err:  # orbax reports a full disk as ValueError
    failure = _reason(err)
  if failure:
    _silence_abandoned_writes()
    shutil.rmtree(new, ignore_errors=True)
    _clear_leftovers(target.parent)
    raise SaveFailed(f"could not write checkpoint {target}: {failure}")
  atomic.swap_in(new, target)
  if not final:
    for old in sorted(_periodic_steps(run_dir), reverse=True)[keep:]:
      atomic.remove_dir(run_dir / layout.PERIODIC / str(old))
  return target


# -- reading -------------------------------------------------------------------

def _periodic_steps(run_dir: pathlib.Path) -> list[int]:
  periodic = run_dir / layout.PERIODIC
  if not periodic.is_dir():
    return []
  names = {p.name.removesuffix(atomic.OLD) for p in periodic.iterdir()}
  return [int(n) for n in names if n.isdigit() and atomic.readable(periodic / n) is not None]


def _item(path: pathlib.Path) -> pathlib.Path:
  # a periodic checkpoint of an older run: CheckpointManager kept its item in a subfolder
  return path / _ITEM if (path / _ITEM).is_dir() else path


def _older_release_step(path: pathlib.Path) -> int:
  """The step of a checkpoint without a manifest that orbax says it committed before
  manifests came in (a release older than MANIFESTS_SINCE wrote it); Damaged otherwise:
  a missing manifest must not switch its checks off."""
  try:
    with _quiet():
      meta = ocp.StandardCheckpointer().metadata(_item(path).resolve())
    stamps = json.loads((_item(path) / "_CHECKPOINT_METADATA").read_text())
    committed = stamps["commit_timestamp_nsecs"]
  except Exception as err:  # orbax raises what its reader met
    raise Damaged(f"checkpoint {path} is damaged: unreadable ({_reason(err)})") from None
  if not isinstance(committed, int) or committed >= MANIFESTS_SINCE_NS:
    raise Damaged(f"checkpoint {path} is damaged: it has no {MANIFEST} (only checkpoints "
                  f"written before {MANIFESTS_SINCE} may lack one)")
  name = path.name.removesuffix(atomic.OLD)
  return int(name) if name.isdigit() else int(meta.custom_metadata["step"])


def verify(path: pathlib.Path) -> int:
  """The step of the checkpoint at `path` after checking every file against its manifest;
  Damaged when one is missing, differs, or is not in it. Only a checkpoint of a release
  older than manifests has none (_older_release_step)."""
  path = pathlib.Path(path)
  if not path.is_dir():
    raise Damaged(f"checkpoint {path} does not exist")
  if not (path / MANIFEST).is_file():
    return _older_release_step(path)
  try:
    manifest = json.loads((path / MANIFEST).read_text())
    step, files = int(manifest["step"]), dict(manifest["files"])
  except (ValueError, KeyError, TypeError, OSError):
    raise Damaged(f"checkpoint {path} is damaged: its {MANIFEST} is unreadable") from None
  for name, want in sorted(files.items()):
    file = path / name
    try:
      same = file.stat().st_size == want["bytes"] and _digest(file) == want["sha256"]
    except OSError:  # gone, or unreadable
      raise Damaged(f"checkpoint {path} is damaged: {name} is missing") from None
    if not same:
      raise Damaged(f"checkpoint {path} is damaged: {name} differs from its checksum")
  unlisted = sorted({str(p.relative_to(path)) for p in _files(path)} - set(files))
  if unlisted:
    raise Damaged(f"checkpoint {path} is damaged: {unlisted[0]} is not in its {MANIFEST}")
  return step


def _step_of(path: pathlib.Path) -> float:
  """The step a checkpoint claims (for ordering; verify() checks it); infinite when it
  cannot be read, so that readers meet it first and name it."""
  try:
    return int(json.loads((path / MANIFEST).read_text())["step"])
  except (ValueError, KeyError, TypeError, OSError):
    try:
      return verify(path)
    except Damaged:
      return math.inf


def candidates(run_dir: pathlib.Path) -> list[pathlib.Path]:
  """A run's checkpoints, newest first (final before a periodic one of the same step; one
  whose step cannot be read first of all), unverified; the `.old` copy of one whose swap a
  kill interrupted stands in for it."""
  run_dir = pathlib.Path(run_dir)
  found = [(step, 0, atomic.readable(run_dir / layout.PERIODIC / str(step)))
           for step in _periodic_steps(run_dir)]
  final = atomic.readable(run_dir / layout.FINAL)
  if final is not None:
    found.append((_step_of(final), 1, final))
  return [path for _, _, path in sorted(found, key=lambda c: c[:2], reverse=True)]


def _identity(path: pathlib.Path) -> tuple[int, int] | None:
  try:
    st = os.stat(path)
  except OSError:
    return None
  return st.st_dev, st.st_ino


def read_newest(run_dir: pathlib.Path, read, damaged) -> tuple[pathlib.Path | None, object]:
  """(checkpoint, read(checkpoint)) of the newest checkpoint of a run that `read` takes
  (it raises Damaged on one it does not), (None, None) when none does; `damaged(path, err)`
  is told of each damaged one on the way.

  A snapshot: the checkpoints of a run that is being written rotate (a swap, a prune) while
  they are read; a folder replaced or removed during its read is not damaged, and the list
  is read again."""
  for _ in range(100):
    for path in candidates(run_dir):
      before = _identity(path)
      try:
        value = read(path)
      except Damaged as err:
        if before is None or _identity(path) != before:
          break  # rotated away while read
        damaged(path, err)
        continue
      if _identity(path) == before:
        return path, value
      break
    else:
      return None, None
  raise Damaged(f"the checkpoints of {run_dir} changed every time they were read")


def latest(run_dir: pathlib.Path, warn=warn) -> pathlib.Path | None:
  """The newest checkpoint of a run that passes verify(); `warn` gets one line for each
  damaged one skipped."""
  return read_newest(run_dir, verify, lambda path, err: warn(f"{err}; skipping it"))[0]


def read_arrays(path: pathlib.Path, prefix: str) -> dict[str, "np.ndarray"]:
  """The arrays of the checkpoint at `path` whose names start with `prefix` (names with the
  prefix removed), without building the state they belong to: e.g. a run's decoder."""
  import numpy as np

  verify(path)
  item = _item(pathlib.Path(path))
  try:
    with _quiet():
      saved = ocp.StandardCheckpointer().restore(item.resolve())
  except Exception as err:  # orbax raises what its reader met
    raise Damaged(f"checkpoint {path} is damaged: unreadable ({_reason(err)})") from None
  return {k[len(prefix):]: np.asarray(v) for k, v in saved.items() if k.startswith(prefix)}


def restore(path: pathlib.Path, target):
  """The state saved at `path`, in the structure of `target` (a state of the same config).

  A damaged checkpoint raises Damaged; one written for another config raises BadInput
  with one line saying so.
  """
  verify(path)
  item = _item(pathlib.Path(path))
  checkpointer = ocp.StandardCheckpointer()
  try:
    with _quiet():
      saved = checkpointer.metadata(item.resolve()).item_metadata
  except Exception as err:  # orbax raises what its reader met
    raise Damaged(f"checkpoint {path} is damaged: unreadable ({_reason(err)})") from None
  if saved is None:
    raise Damaged(f"checkpoint {path} is damaged: it holds no arrays")
  wanted = _arrays(target)
  for name in sorted(set(saved) | set(wanted)):
    have = (tuple(saved[name].shape), saved[name].dtype) if name in saved else "absent"
    want = (tuple(wanted[name].shape), wanted[name].dtype) if name in wanted else "absent"
    if have != want:
      raise BadInput(f"checkpoint {path} does not match this config: {name} is {have} there, "
                     f"{want} here")
  abstract = {k: ocp.utils.to_shape_dtype_struct(v) for k, v in wanted.items()}
  try:
    with _quiet():
      restored = checkpointer.restore(item.resolve(), abstract)
  except Exception as err:  # orbax raises what its reader met
    raise Damaged(f"checkpoint {path} is damaged: unreadable ({_reason(err)})") from None
  leaves = [restored.get(name, leaf) for name, leaf in _named_leaves(target)]
  return jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(target), leaves)


def remove(path: pathlib.Path) -> None:
  """Delete a checkpoint (e.g. a damaged one a resumed run will write anew)."""
  atomic.remove_dir(pathlib.Path(path))
