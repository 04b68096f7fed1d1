"""Stops (Ctrl-C, SIGTERM) wherever they land.

The command's signal handlers (discosyn/cli.py) raise the stop at once where Python can take
it: between steps, in an evaluation, after a compile or a save (saves hold signals until they
end). Two places cannot take it, and this module covers them:

- a garbage-collector callback (JAX registers one): Python prints an exception raised there
  and drops it. The stop is parked (`defer`) and the training loop raises it at its next
  step (`check`).
- a host callback inside a jitted computation (the native physics, `jax.pure_callback`):
  the stop aborts the computation, which JAX reports as its own error (a JaxRuntimeError
  wrapping the KeyboardInterrupt). The stop is recorded before it is raised (`raised`), so
  that whoever catches that error takes it for the stop it is (`taken`).

A second signal while a stop is under way is ignored (`under_way`): the first one's clean-up
(the run's folder put right, its one line) is short and must not be cut.
"""

from __future__ import annotations

import gc

_pending: list[BaseException] = []  # parked stops, not raised yet
_raised: list[BaseException] = []  # the stop under way


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


def raised(exception: BaseException) -> BaseException:
  """Record `exception` as the stop under way; return it, to be raised."""
  _raised.append(exception)
  return exception


def under_way() -> bool:
  return bool(_raised)


def taken(error: BaseException) -> BaseException | None:
  """The stop that `error` is: itself for a KeyboardInterrupt; else, while a stop is under
  way, that stop (the error is its consequence, e.g. the computation it aborted); else None."""
  if isinstance(error, KeyboardInterrupt):
    return error
  return _raised[-1] if _raised else None


def check() -> None:
  """Raise a parked stop, if any."""
  if _pending:
    raise raised(_pending.pop())


def reset() -> None:
  """Forget every stop: a caller (a notebook, a test) goes on in the same process."""
  _pending.clear()
  _raised.clear()
