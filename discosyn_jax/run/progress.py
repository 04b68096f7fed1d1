"""A run's progress as it trains: a tqdm bar on a terminal, plain lines elsewhere."""

from __future__ import annotations

import sys
import time


def bar(enabled: bool, start: int, total: int):
  """A tqdm bar on a terminal; elsewhere (a log file, a notebook's captured stderr) one
  line every tenth of the run, since a bar's carriage returns would flood the log."""
  if not enabled:
    return None
  if not sys.stderr.isatty():
    return ProgressLines(start, total, every=max(1, total // 10))
  from tqdm import tqdm

  return tqdm(total=total, initial=start, unit="step", dynamic_ncols=True)


class ProgressLines:
  """The part of tqdm's interface the loop uses, as plain lines on stderr."""

  def __init__(self, start: int, total: int, every: int):
    self.n, self.start, self.total, self.every, self.postfix = start, start, total, every, ""
    self.began = time.perf_counter()

  def update(self, n: int) -> None:
    self.n += n
    if self.n % self.every == 0 or self.n == self.total:
      rate = (self.n - self.start) / (time.perf_counter() - self.began)
      print(f"step {self.n}/{self.total}, {rate:.2f} steps/s {self.postfix}".rstrip(),
            file=sys.stderr, flush=True)

  def set_postfix_str(self, text: str, refresh: bool = True) -> None:
    del refresh  # a line is written by update() only
    self.postfix = text

  def close(self) -> None:
    pass
