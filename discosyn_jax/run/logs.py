"""A run's logs: the JSON-lines files the loop writes (read back here for plots and reports)
and the same numbers as TensorBoard event files (tensorboardX: no TensorFlow needed).

`tensorboard --logdir RUN/tb` shows a run; `--logdir runs` compares runs.
"""

from __future__ import annotations

import json
import lzma
import pathlib
import time

from discosyn_jax import atomic
from discosyn_jax.checks import BadInput
from discosyn_jax.run import layout, record_files
from discosyn_jax.run.record_files import RecordError

# A kept run's bulky log compressed (a run's record keeps metrics.jsonl as
# metrics.jsonl.xz, `archive`); readers take either.
ARCHIVED = ".xz"
# significant digits of an archive's fractional numbers: more than any figure reads, and
# the archive is less than half the size of one with every float's 17 digits
ARCHIVED_DIGITS = 5

# What an archive keeps of a run's metrics.jsonl (a record's metrics: what the reports,
# figures and studies read, at a fifth of the size): every RECORD_EVERY-th train step (an
# even sample: means over a window stay means), the last RECORD_ENDS (what the tables'
# means over the last steps read), the row where a task's first reward shows; and not the
# update's loss diagnostics (none of them is read from a record; the run's own log keeps
# them).
RECORD_EVERY, RECORD_ENDS = 4, 16
_LEFT_OUT = frozenset({"approx_kl", "clip_fraction", "policy_loss", "value_loss", "loss",
                       "env_steps_per_s"})

# bookkeeping columns of the rows: the x axes, not curves of their own
_AXES = frozenset({"step", "env_steps", "wall_s", "finite"})


def read_jsonl(path: pathlib.Path, check=None) -> list[dict]:
  """The rows of a JSON-lines file. A last line cut short (a run killed while writing it)
  is left out; any other line that is not a JSON object, or that `check(row)` finds wrong
  (its words, None for nothing), is a RecordError naming the file and the line."""
  path = pathlib.Path(path)
  if not path.is_file():
    raise BadInput(f"{path} does not exist")
  opener = lzma.open if path.suffix == ARCHIVED else open
  try:
    with opener(path, "rt") as f:
      lines = f.read().splitlines(keepends=True)
  except UnicodeDecodeError:
    raise RecordError(f"{path}: not text (a byte that is not UTF-8); expected JSON lines") from None
  except (lzma.LZMAError, EOFError) as err:  # a damaged or cut archive
    raise RecordError(f"{path}: not a whole .xz archive ({err})") from None
  rows = []
  for number, line in enumerate(lines, 1):
    if not line.strip():
      continue
    try:
      row = json.loads(line)
    except (json.JSONDecodeError, RecursionError):
      if number == len(lines) and not line.endswith("\n"):
        break
      raise RecordError(f"{path}, line {number}: not JSON") from None
    if not isinstance(row, dict):
      raise RecordError(f"{path}, line {number}: not a JSON object")
    wrong = check(row) if check else None
    if wrong:
      raise RecordError(f"{path}, line {number}: {wrong}")
    rows.append(row)
  return rows


def read_log(path: pathlib.Path, as_archived: bool = False) -> list[dict]:
  """The rows of the log at `path` or of its archive `path`.xz; none when neither exists.
  `as_archived`: the numbers at the archive's precision either way (a run and its record
  then read the same). An eval.jsonl's rows are checked (record_files.evaluation_check)
  wherever it is read: a damaged one never reaches a table."""
  path = pathlib.Path(path)
  check = record_files.evaluation_check() if path.name == layout.EVAL_FILE else None
  for candidate in (path, path.with_name(path.name + ARCHIVED)):
    if candidate.is_file():
      rows = read_jsonl(candidate, check)
      return [{k: _archived(v) for k, v in row.items()} for row in rows] if as_archived else rows
  return []


def archive(path: pathlib.Path, unroll_length: int) -> pathlib.Path:
  """Write `path`.xz beside the log at `path` (in one step: a kill leaves the old one or
  none): the rows a record keeps (`kept`), every fractional number to ARCHIVED_DIGITS
  significant digits (counts, steps and integral values exact); the log itself stays, the
  loop appends to it. `path` may be the archive itself (an older record, thinned again)."""
  path = pathlib.Path(path)
  target = path if path.suffix == ARCHIVED else path.with_name(path.name + ARCHIVED)
  rows = kept(read_jsonl(path), unroll_length)
  with atomic.replacing(target) as tmp, lzma.open(tmp, "wt", preset=9) as f:
    for row in rows:
      f.write(json.dumps({key: _archived(value) for key, value in row.items()}) + "\n")
  return target


def kept(rows: list[dict], unroll_length: int) -> list[dict]:
  """The rows and columns of a metrics log that its archive keeps (RECORD_EVERY), of a run
  of rollouts of `unroll_length` steps (a task's first_reward_t is that until it is paid);
  the same rows again when given them (thinning an archive twice changes nothing)."""
  found, out = set(), []
  for n, row in enumerate(rows):
    news = {key for key, value in row.items() if key.endswith("/first_reward_t")
            and key not in found and value < unroll_length}
    found |= news
    if (row.get("step", n) % RECORD_EVERY == 0 or n >= len(rows) - RECORD_ENDS
        or news):
      out.append({key: value for key, value in row.items()
                  if key.rpartition("/")[2] not in _LEFT_OUT})
  return out


def _archived(value):
  if isinstance(value, float) and not value.is_integer():
    return float(f"{value:.{ARCHIVED_DIGITS}g}")
  return value


def tag(name: str, kind: str) -> str:
  """TensorBoard tag of a column: per-task training figures keep their `task/` group,
  figures of the whole update go under train/, evaluations under eval/."""
  if kind == "eval":
    return f"eval/{name}"
  return name if "/" in name else f"train/{name}"


def cut(path: pathlib.Path, step: int) -> list[dict]:
  """Keep the rows of a JSON-lines log up to train step `step` (a resumed run's restored
  step), and no line that is not a whole JSON object (a line a kill cut short); return the
  rows kept. The file is replaced in one step, so a kill here loses nothing."""
  path = pathlib.Path(path)
  if not path.is_file():
    return []
  kept, rows = [], []
  for line in path.read_text().splitlines():
    try:
      row = json.loads(line)
    except json.JSONDecodeError:
      continue
    if isinstance(row, dict) and row.get("step", step + 1) <= step:
      kept.append(line + "\n")
      rows.append(row)
  atomic.write_text(path, "".join(kept))
  return rows


class TensorBoard:
  """Writes the rows of metrics.jsonl and eval.jsonl as scalars over env steps.

  Events are written in the calling thread (tensorboardX's EventsWriter, not its
  SummaryWriter's queue and thread), so a full disk raises here like any other write.
  `history` (metrics rows, eval rows), for a resumed run, replaces the event files by those
  rows: the logs then hold what an unbroken run's hold, nothing after the restored step.
  """

  def __init__(self, run_dir: pathlib.Path, history: tuple[list[dict], list[dict]] | None = None):
    from tensorboardX.event_file_writer import EventsWriter

    folder = pathlib.Path(run_dir) / layout.TENSORBOARD_DIR
    if history is None:
      folder.mkdir(exist_ok=True)
      self.events = EventsWriter(str(folder / "events"))
      return
    atomic.settle(folder)
    new = atomic.sibling(folder, atomic.NEW)
    new.mkdir()
    self.events = EventsWriter(str(new / "events"))
    for rows, kind in zip(history, ("train", "eval")):
      for row in rows:
        self.write(row, kind)
    atomic.swap_in(new, folder)  # the open event file moves with its folder

  def write(self, row: dict, kind: str) -> None:
    """`kind` is "train" (a metrics.jsonl row) or "eval" (an eval.jsonl row)."""
    from tensorboardX.proto.event_pb2 import Event
    from tensorboardX.proto.summary_pb2 import Summary

    values = [Summary.Value(tag=tag(name, kind), simple_value=float(value))
              for name, value in row.items() if name not in _AXES]
    self.events.write_event(Event(wall_time=time.time(), step=int(row["env_steps"]),
                                  summary=Summary(value=values)))
    self.events.flush()

  def __enter__(self) -> "TensorBoard":
    return self

  def __exit__(self, *exc) -> None:
    self.events.close()
