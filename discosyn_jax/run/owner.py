"""Who owns a run folder: one writer at a time, and a `--force` that never destroys.

A writer (`discosyn train`, fresh, resumed or forced) holds an exclusive `flock` on
RUN/writer.lock from before it writes anything to its end; the file says who it is (pid,
host, start time), so that a second writer is refused in one line naming it, and readers
can say that what they read is being written. The kernel drops the lock of a process that
dies, however it dies: a lock file nobody holds is a stale one, and is taken over.

`--force` sets the run it replaces aside in RUN/replaced/ and removes it only once the new
run has its first good checkpoint; a new run that ends before that (an error, Ctrl-C) is
removed and the old one put back, and a kill in between is settled by the next writer
the same way (`settle`).
"""

from __future__ import annotations

import datetime
import fcntl
import json
import os
import pathlib
import shutil
import socket
import time

from discosyn_jax import atomic
from discosyn_jax.checks import BadInput
from discosyn_jax.run import checkpoints, layout

_TRIES = 20  # a reader's probe holds the lock for microseconds: a writer tries again


class Busy(BadInput):
  """Another live process writes the run: the folder named cannot be used now."""


def is_run(folder: pathlib.Path) -> bool:
  """Whether `folder` holds a run this product made (config.json and another of its names)."""
  folder = pathlib.Path(folder)
  return (folder / layout.CONFIG_FILE).is_file() and any((folder / n).exists() for n in layout.RUN_NAMES)


def contents(folder: pathlib.Path) -> list[pathlib.Path]:
  """What a folder holds besides its writer's lock."""
  return [p for p in pathlib.Path(folder).iterdir() if p.name != layout.LOCK]


def _describe(text: str) -> str:
  try:
    who = json.loads(text)
    return f"process {who['pid']} on {who['host']}, started {who['started']}"
  except (ValueError, KeyError, TypeError):
    return "another process"


def writer_of(run_dir: pathlib.Path) -> str | None:
  """Who writes the run now ("process N on HOST, started T"), None when no one does.
  Writes nothing: a read-only run can be asked."""
  try:
    fd = os.open(pathlib.Path(run_dir) / layout.LOCK, os.O_RDONLY)
  except OSError:
    return None
  try:
    try:
      fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
      return _describe(os.pread(fd, 4096, 0).decode(errors="replace"))
    fcntl.flock(fd, fcntl.LOCK_UN)
    return None
  finally:
    os.close(fd)


def _busy(run_dir: pathlib.Path, writer: str) -> Busy:
  return Busy(f"{run_dir} is being written by {writer}; wait for it to end, or stop it")


def refuse_if_written(run_dir: pathlib.Path) -> None:
  """Busy, naming the writer, when a live process writes `run_dir`."""
  writer = writer_of(run_dir)
  if writer:
    raise _busy(run_dir, writer)


class Writer:
  """The lock of the one process that writes `run_dir`, held inside a `with` block; the
  folder (and its parents) is made here if it does not exist, and removed again if the
  block leaves nothing in it. Raises Busy when a live process holds it."""

  def __init__(self, run_dir: pathlib.Path, warn=checkpoints.warn):
    self.run_dir, self.warn = pathlib.Path(run_dir), warn
    self.created = None  # the topmost folder made here
    self.new = False  # this writer started a new run (begin)
    self.kept = False  # the new run has a good checkpoint
    self._fd = None

  def __enter__(self) -> "Writer":
    for path in (self.run_dir, *self.run_dir.parents):
      if path.exists():
        break
      self.created = path
    try:
      self.run_dir.mkdir(parents=True, exist_ok=True)
      self._lock()
      settle(self.run_dir, self.warn)
    except OSError as err:
      self.__exit__(None, None, None)
      raise BadInput(f"cannot write the run directory {self.run_dir}: "
                     f"{err.strerror or err}") from None
    except BaseException:
      self.__exit__(None, None, None)
      raise
    return self

  def _lock(self) -> None:
    path, holder = self.run_dir / layout.LOCK, ""
    for _ in range(_TRIES):
      fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
      try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
      except BlockingIOError:
        holder = os.pread(fd, 4096, 0).decode(errors="replace")
        os.close(fd)
        time.sleep(0.05)
        continue
      try:  # the file we locked is still the lock: its last owner unlinks it as it ends
        if os.stat(path).st_ino == os.fstat(fd).st_ino:
          break
      except FileNotFoundError:
        pass
      os.close(fd)
    else:
      raise _busy(self.run_dir, _describe(holder))
    self._fd = fd
    stale = os.pread(fd, 4096, 0).decode(errors="replace")
    if stale.strip():  # a writer that ended cleanly removed its lock file
      self.warn(f"{self.run_dir} was left by {_describe(stale)}, which has ended without "
                f"finishing; this process takes it over")
    started = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    me = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "started": started})
    os.ftruncate(fd, 0)
    os.pwrite(fd, me.encode(), 0)
    os.fsync(fd)

  def __exit__(self, *exc) -> None:
    if self._fd is not None:
      try:
        os.unlink(self.run_dir / layout.LOCK)
      except OSError:  # a folder made read-only meanwhile: the next writer takes it over
        pass
      os.close(self._fd)
      self._fd = None
    if self.created is not None and self.run_dir.is_dir() and not any(self.run_dir.iterdir()):
      shutil.rmtree(self.created, ignore_errors=True)

  def begin(self, write_config, replace: bool) -> None:
    """Start a new run: set aside the run there (`replace`), then `write_config()`."""
    self.new = True
    try:
      if replace and contents(self.run_dir):
        moving = atomic.sibling(self.run_dir / layout.ASIDE, atomic.NEW)
        moving.mkdir()
        _move_all(self.run_dir, moving)
        os.rename(moving, self.run_dir / layout.ASIDE)
      write_config()
    except OSError as err:
      self.undo()
      raise BadInput(f"cannot write the run directory {self.run_dir}: "
                     f"{err.strerror or err}") from None

  def keep(self) -> None:
    """The new run has a good checkpoint: the run it replaces goes."""
    if self.new and not self.kept:
      atomic.remove_dir(self.run_dir / layout.ASIDE)
      self.kept = True

  def undo(self) -> bool:
    """A new run that ended before its first good checkpoint leaves no trace: what it wrote
    goes, a run it was replacing comes back. Whether there was one."""
    if not atomic.sibling(self.run_dir / layout.ASIDE, atomic.NEW).exists():  # else all is the old run's
      _remove_new(self.run_dir)
    return settle(self.run_dir, warn=lambda _: None)


def take_over(run_dir: pathlib.Path) -> None:
  """Settle what a dead writer left in `run_dir` (its lock, a replacement cut short), as a
  writer does first: for a caller that reads the run's config before it writes."""
  left = (layout.LOCK, layout.ASIDE, layout.ASIDE + atomic.NEW)
  if any((pathlib.Path(run_dir) / name).exists() for name in left):
    with Writer(run_dir):
      pass


def _remove_new(run_dir: pathlib.Path) -> None:
  """Remove what a new run wrote: all but the lock and a run set aside."""
  for path in contents(run_dir):
    if path.name not in (layout.ASIDE, layout.ASIDE + atomic.NEW):
      shutil.rmtree(path) if path.is_dir() else path.unlink()


def _move_all(source: pathlib.Path, target: pathlib.Path) -> None:
  for path in source.iterdir():
    if path.name not in (layout.LOCK, target.name):
      os.rename(path, target / path.name)


def settle(run_dir: pathlib.Path, warn=checkpoints.warn) -> bool:
  """Finish a replacement a kill interrupted (the writer's job, under its lock): a run set
  aside goes once the new run has a good checkpoint, else it comes back (the new run's
  files removed). Whether a run came back.

  While RUN/replaced.new exists, everything in it and in RUN is the old run's (the move
  aside, or back, was cut short); RUN/replaced holds the old run whole."""
  run_dir = pathlib.Path(run_dir)
  aside, moving = run_dir / layout.ASIDE, atomic.sibling(run_dir / layout.ASIDE, atomic.NEW)
  shutil.rmtree(atomic.sibling(aside, atomic.TRASH), ignore_errors=True)
  if aside.is_dir():
    if checkpoints.latest(run_dir, warn=lambda _: None) is not None:
      atomic.remove_dir(aside)
      return False
    _remove_new(run_dir)
    os.rename(aside, moving)
  if not moving.is_dir():
    return False
  for path in moving.iterdir():
    os.rename(path, run_dir / path.name)
  moving.rmdir()
  warn(f"the run in {run_dir} that --force was replacing is back: the new run ended before "
       f"its first checkpoint")
  return True
