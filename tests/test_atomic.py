"""A file written in one step (atomic.py): under a temporary name of its own write, so that
two processes writing one file never share it, removed when the write fails, and made with
the user's umask."""

import json
import os
import subprocess
import sys

import pytest

from discosyn_jax import atomic
from discosyn_jax.run import layout


def test_two_writes_of_one_file_never_share_a_temporary_name(tmp_path):
  path = tmp_path / layout.CONFIG_FILE
  names = {atomic.unique(path) for _ in range(100)} | {atomic.unique(path, ".npz")}
  assert len(names) == 101 and all(p.parent == tmp_path and p.name.startswith(path.name) for p in names)


def test_another_process_writing_the_same_file_leaves_this_write_whole(tmp_path):
  """This process is half way through writing plan.json when another writes it whole: each
  write renames its own file over it, and none is left beside it."""
  path = tmp_path / "plan.json"
  with atomic.replacing(path) as mine:
    mine.write_text('{"by": "this process"}')
    other = subprocess.run(
        [sys.executable, "-c", "import sys, pathlib; from discosyn_jax import atomic; "
         "atomic.write_text(pathlib.Path(sys.argv[1]), '{\"by\": \"the other\"}')", str(path)],
        capture_output=True, text=True)
    assert other.returncode == 0, other.stderr
    assert json.loads(path.read_text()) == {"by": "the other"}
    assert mine.read_text() == '{"by": "this process"}'  # untouched by the other write
  assert json.loads(path.read_text()) == {"by": "this process"}
  assert os.listdir(tmp_path) == ["plan.json"]


def test_a_write_that_fails_leaves_no_temporary_file_and_the_old_content(tmp_path):
  path = tmp_path / "closing.json"
  path.write_text("old")
  with pytest.raises(RuntimeError):
    with atomic.replacing(path) as tmp:
      tmp.write_text("half")
      raise RuntimeError("the disk filled")
  assert path.read_text() == "old" and os.listdir(tmp_path) == ["closing.json"]
  (tmp_path / "plan.json").mkdir()  # a folder where the file goes
  with pytest.raises(IsADirectoryError):
    atomic.write_text(tmp_path / "plan.json", "{}")
  assert sorted(os.listdir(tmp_path)) == ["closing.json", "plan.json"]


def test_a_file_is_written_with_the_users_umask(tmp_path):
  old = os.umask(0o027)
  try:
    atomic.write_text(tmp_path / "config.json", "{}")
  finally:
    os.umask(old)
  assert (tmp_path / "config.json").stat().st_mode & 0o777 == 0o640
