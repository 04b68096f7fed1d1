"""Writes that a kill at any instant leaves either undone or done, never half done.

A file is written beside its target under a name of this write's own (`unique`: two
processes writing one file never write into the same temporary file) and renamed over it;
a write that fails removes it. A folder is written as
`NAME.new`, then swapped in: `NAME` -> `NAME.old`, `NAME.new` -> `NAME`, and `NAME.old`
removed (through `NAME.trash`). Whatever instant a kill hits, `NAME` or `NAME.old` holds a
complete folder; `settle` finishes or undoes an interrupted swap.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import secrets
import shutil

NEW, OLD, TRASH = ".new", ".old", ".trash"


def fsync_dir(path: pathlib.Path) -> None:
  """Make the renames and new entries of a folder durable (a power cut, not only a kill)."""
  fd = os.open(path, os.O_RDONLY)
  try:
    os.fsync(fd)
  finally:
    os.close(fd)


def unique(path: pathlib.Path, suffix: str = "") -> pathlib.Path:
  """A name beside `path` for one write of it: the process and a random part in it, so that
  no other write, in this process or another, picks it; `suffix` ends it (np.savez adds
  ".npz" to a name without it)."""
  path = pathlib.Path(path)
  return path.with_name(f"{path.name}.{os.getpid()}-{secrets.token_hex(4)}{NEW}{suffix}")


@contextlib.contextmanager
def replacing(path: pathlib.Path, suffix: str = ""):
  """The temporary path (`unique`) to write `path`'s new content to: renamed over `path`
  when the block ends, removed when it fails."""
  path = pathlib.Path(path)
  tmp = unique(path, suffix)
  try:
    yield tmp
    os.replace(tmp, path)
  except BaseException:
    tmp.unlink(missing_ok=True)  # nothing half-written left beside it
    raise
  fsync_dir(path.parent)


def write_text(path: pathlib.Path, text: str) -> None:
  """Replace the file at `path` by `text` in one step (the file made with the user's umask)."""
  with replacing(path) as tmp, open(tmp, "x") as f:
    f.write(text)
    f.flush()
    os.fsync(f.fileno())


def sibling(path: pathlib.Path, suffix: str) -> pathlib.Path:
  return path.with_name(path.name + suffix)


def remove_dir(path: pathlib.Path) -> None:
  """Remove a folder: renamed away first, so that a kill never leaves it half deleted."""
  if not path.exists():
    return
  trash = sibling(path, TRASH)
  shutil.rmtree(trash, ignore_errors=True)
  os.rename(path, trash)
  shutil.rmtree(trash)


def swap_in(new: pathlib.Path, target: pathlib.Path) -> None:
  """Put the complete folder `new` in the place of `target` (which may not exist)."""
  old = sibling(target, OLD)
  if target.exists():
    remove_dir(old)
    os.rename(target, old)
  os.rename(new, target)
  fsync_dir(target.parent)
  remove_dir(old)


def settle(target: pathlib.Path) -> None:
  """Finish what a kill interrupted around `target`: an unfinished `.new` or `.trash` goes,
  an `.old` left without its successor comes back."""
  for suffix in (NEW, TRASH):
    shutil.rmtree(sibling(target, suffix), ignore_errors=True)
  old = sibling(target, OLD)
  if old.exists():
    if target.exists():
      remove_dir(old)
    else:
      os.rename(old, target)


def readable(target: pathlib.Path) -> pathlib.Path | None:
  """Where a reader that must not write finds `target`: itself, or the `.old` an
  interrupted swap left (None when neither exists)."""
  for path in (target, sibling(target, OLD)):
    if path.exists():
      return path
  return None
