"""The checks of a run's own files as read back (eval.jsonl's rows, closing.json,
experiment.json): a file damaged or edited by hand is refused in one line that names the
file, the field and what was expected, so that no damaged number reaches a table or a
verdict."""

from __future__ import annotations

import json
import math
import pathlib
from typing import Any

from discosyn_jax import checks
from discosyn_jax.checks import BadInput


class RecordError(BadInput):
  """A run's file that does not hold what the run writes there: one line naming the file,
  the field and what was expected."""


# what the loop writes in an evaluation row and in closing.json besides "<task>/<figure>"
EVAL_FIELDS = frozenset({"step", "env_steps", "wall_s"})
CLOSING_FIELDS = frozenset({"step", "env_steps", "episodes"})
# experiment.json's labels and their types; other fields are a user's own, left alone
LABELS = {"experiment": str, "method": str, "set": str, "seed": int, "scale": (str, type(None)),
          "row": str}


def read_object(path: pathlib.Path) -> dict[str, Any]:
  """The JSON object in the file at `path`."""
  path = pathlib.Path(path)
  try:
    text = path.read_text()
  except UnicodeDecodeError:
    raise RecordError(f"{path}: not text (a byte that is not UTF-8); expected a JSON object") from None
  if not text.strip():
    raise RecordError(f"{path}: empty; expected a JSON object")
  try:
    value = json.loads(text)
  except (json.JSONDecodeError, RecursionError) as err:
    raise RecordError(f"{path}: not JSON ({str(err).splitlines()[0]}); expected a JSON object") from None
  if not isinstance(value, dict):
    raise RecordError(f"{path}: a JSON {type(value).__name__}, not the object expected")
  return value


def _shown(value) -> str:
  return checks.shortened(repr(value))


def _is_number(value) -> bool:
  return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _is_count(value) -> bool:
  return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def figures(row: dict[str, Any], bare: frozenset[str]) -> str | None:
  """What is wrong with an evaluation's row (eval.jsonl, closing.json), None for nothing:
  its `bare` fields counts (wall_s seconds), its "<task>/success" a rate in [0, 1], every
  other "<task>/<figure>" a finite number."""
  for key, value in row.items():
    if "/" not in key:
      if key not in bare:
        return f"unknown field {key!r} (expected {', '.join(sorted(bare))} and <task>/<figure>)"
      if key == "wall_s":
        if not _is_number(value) or value < 0:
          return f"wall_s is {_shown(value)}, not a number of seconds"
      elif not _is_count(value):
        return f"{key} is {_shown(value)}, not a whole number >= 0"
    elif key.endswith("/success"):
      if not _is_number(value) or not 0 <= value <= 1:
        return f"{key} is {_shown(value)}, not a success rate in [0, 1]"
    elif not _is_number(value):
      return f"{key} is {_shown(value)}, not a finite number"
  return None


def evaluation_check():
  """A check of eval.jsonl's rows in file order (logs.read_jsonl's `check`): each names its
  train step, later than the row before it's, and holds figures() fit for a table."""
  last = [None]

  def check(row: dict[str, Any]) -> str | None:
    if "step" not in row:
      return "no step (each evaluation names its train step, a whole number)"
    wrong = figures(row, EVAL_FIELDS)
    if wrong:
      return wrong
    if last[0] is not None and row["step"] <= last[0]:
      return f"step {row['step']} after step {last[0]} (expected evaluations in the order of their steps)"
    last[0] = row["step"]
    return None

  return check


def read_closing(path: pathlib.Path) -> dict[str, Any]:
  """closing.json: the closing evaluation, checked as an evaluation's row."""
  row = read_object(path)
  wrong = "no step (the train step it closed)" if "step" not in row else figures(row, CLOSING_FIELDS)
  if wrong:
    raise RecordError(f"{path}: {wrong}")
  return row


def read_labels(path: pathlib.Path) -> dict[str, Any]:
  """experiment.json: what `discosyn experiment` ran a run as, each label of its type."""
  labels = read_object(path)
  for key, kind in LABELS.items():
    value = labels.get(key)
    if key in labels and (not isinstance(value, kind) or isinstance(value, bool)):
      what = "a whole number" if kind is int else "a string"
      raise RecordError(f"{path}: {key} is {_shown(value)}, not {what}")
  return labels
