"""A run's logs: the JSON-lines files the loop writes (read back here for plots and reports)
and the same numbers as TensorBoard event files (tensorboardX: no TensorFlow needed).

`tensorboard --logdir RUN/tb` shows a run; `--logdir runs` compares runs.
"""

from __future__ import annotations

import json
import pathlib

METRICS_FILE = "metrics.jsonl"  # one row per train step
EVAL_FILE = "eval.jsonl"  # one row per deterministic evaluation
TENSORBOARD_DIR = "tb"

# bookkeeping columns of the rows: the x axes, not curves of their own
_AXES = frozenset({"step", "env_steps", "wall_s", "finite"})


def read_jsonl(path: pathlib.Path) -> list[dict]:
  """The rows of a JSON-lines file. A last line cut short (a run killed while writing it)
  is left out; any other line that is not a JSON object is an error."""
  path = pathlib.Path(path)
  if not path.is_file():
    raise ValueError(f"{path} does not exist")
  lines = path.read_text().splitlines(keepends=True)
  rows = []
  for number, line in enumerate(lines, 1):
    if not line.strip():
      continue
    try:
      row = json.loads(line)
    except json.JSONDecodeError:
      if number == len(lines) and not line.endswith("\n"):
        break
      raise ValueError(f"{path}, line {number}: not JSON") from None
    if not isinstance(row, dict):
      raise ValueError(f"{path}, line {number}: not a JSON object")
    rows.append(row)
  return rows


def tag(name: str, kind: str) -> str:
  """TensorBoard tag of a column: per-task training figures keep their `task/` group,
  figures of the whole update go under train/, evaluations under eval/."""
  if kind == "eval":
    return f"eval/{name}"
  return name if "/" in name else f"train/{name}"


class TensorBoard:
  """Writes the rows of metrics.jsonl and eval.jsonl as scalars over env steps."""

  def __init__(self, run_dir: pathlib.Path):
    from tensorboardX import SummaryWriter

    self.writer = SummaryWriter(str(pathlib.Path(run_dir) / TENSORBOARD_DIR))

  def write(self, row: dict, kind: str) -> None:
    """`kind` is "train" (a metrics.jsonl row) or "eval" (an eval.jsonl row)."""
    step = int(row["env_steps"])
    for name, value in row.items():
      if name not in _AXES:
        self.writer.add_scalar(tag(name, kind), float(value), step)
    self.writer.flush()

  def __enter__(self) -> "TensorBoard":
    return self

  def __exit__(self, *exc) -> None:
    self.writer.close()
