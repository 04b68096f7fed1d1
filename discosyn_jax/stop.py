"""Stops that a signal could not raise where it arrived.

Python prints and drops an exception raised inside a garbage-collector callback (JAX
registers one), so a Ctrl-C or SIGTERM that lands there would be lost and the run would go
on. The command's signal handlers (discosyn/cli.py) park such a stop here; the training loop
calls `check()` at every step and raises it there.
"""

from __future__ import annotations

import gc

_pending: list[BaseException] = []


def in_gc_callback(frame) -> bool:
  """Whether `frame` (a signal handler's) runs inside a garbage-collector callback."""
  codes = {getattr(callback, "__code__", None) for callback in gc.callbacks}
  while frame is not None:
    if frame.f_code in codes:
      return True
    frame = frame.f_back
  return False


def defer(exception: BaseException) -> None:
  _pending.append(exception)


def check() -> None:
  """Raise a parked stop, if any."""
  if _pending:
    raise _pending.pop()
