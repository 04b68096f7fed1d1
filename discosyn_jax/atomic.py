"""Writes that a kill at any instant leaves either undone or done, never half done.

A file is written beside its target and renamed over it. A folder is written as
`NAME.new`, then swapped in: `NAME` -> `NAME.old`, `NAME.new` -> `NAME`, and `NAME.old`
removed (through `NAME.trash`). Whatever instant a kill hits, `NAME` or `NAME.old` holds a
complete folder; `settle` finishes or undoes an interrupted swap.
"""

from __future__ import annotations

import os
import pathlib
import shutil

NEW, OLD, TRASH = ".new", ".old", ".trash"


def fsync_dir(path: pathlib.Path) -> None:
  """Make the renames and new entries of a folder durable (a power cut, not only a kill)."""
  fd = os.open(path, os.O_RDONLY)
  try:
    os.fsync(fd)
  finally:
    os.close(fd)


def write_text(path: pathlib.Path, text: str) -> None:
  """Replace the file at `path` by `text` in one step."""
  path = pathlib.Path(path)
  tmp = path.with_name(path.name + NEW)
  with open(tmp, "w") as f:
    f.write(text)
    f.flush()
    os.fsync(f.fileno())
  os.replace(tmp, path)
  fsync_dir(path.parent)


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
