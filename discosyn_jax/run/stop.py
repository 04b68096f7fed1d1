"""Stops (Ctrl-C, SIGTERM) wherever they land.

Inside `handled()` (the `discosyn` command's whole run; `training.loop.train` when a script
or a notebook calls it) Ctrl-C raises KeyboardInterrupt and SIGTERM `Terminated`, at once,
where the signal lands: between steps, in an evaluation, after a compile or a save (saves
hold signals until they end). The stop is recorded as it is raised (`raised`), for two kinds
of place that cannot take it:

- where Python drops an exception: a garbage-collector callback (JAX registers one), a
  finalizer (`__del__`, a weakref's callback). The run would go on, deaf to a second signal;
  the training loop raises the stop again at its next step (`check`).
- a host callback inside a jitted computation (the native physics, `jax.pure_callback`):
  the stop aborts the computation, which JAX reports as its own error (a JaxRuntimeError
  wrapping the KeyboardInterrupt); whoever catches that error takes it for the stop it is
  (`taken`).

A second signal while a stop is under way is ignored (`under_way`): the first one's clean-up
(the run's folder put right, its one line) is short and must not be cut.
"""

from __future__ import annotations

import contextlib
import gc
import logging
import signal
import sys
import threading

_raised: list[BaseException] = []  # the stop under way
_open: list[bool] = []  # a handled() block is open: an inner one leaves its handlers alone


class Terminated(KeyboardInterrupt):
  """SIGTERM (a scheduler ending the job): it stops a run as Ctrl-C does."""


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
  """Raise the stop under way, if any: code that runs on after it was raised (a training
  loop's next step) runs because Python dropped it where it landed."""
  if _raised:
    raise _raised[-1]


def reset() -> None:
  """Forget every stop: a caller (a notebook, a test) goes on in the same process."""
  _raised.clear()


def quiet() -> None:
  """From here on, the stop's own line alone: objects the garbage collector frees while a
  stopped run ends (orbax's event loops, their pipes closed) printed "Exception ignored"
  tracebacks, and JAX logs the traceback of a host callback that a stop interrupted."""
  gc.disable()
  sys.unraisablehook = lambda unraisable: None
  logging.disable(logging.CRITICAL)


def stopper(exception_type):
  """A signal handler that raises the stop where it lands; a second signal while a stop is
  under way lets the first one end."""
  def handler(signum, frame):
    del signum, frame
    quiet()  # the run ends: from here on, one line (handled() sets it back)
    if under_way():
      return
    raise raised(exception_type())

  return handler


@contextlib.contextmanager
def handled():
  """Ctrl-C and SIGTERM stop what runs inside the block, cleanly (the stoppers above); on
  leaving it, the signal handlers, the garbage collector and the logging are as they were
  and the stops are forgotten. Only the main thread may set handlers (a notebook may run
  elsewhere): there, and inside a block already open, this leaves everything as it is."""
  if _open or threading.current_thread() is not threading.main_thread():
    yield
    return
  previous = {sig: signal.signal(sig, stopper(kind))
              for sig, kind in ((signal.SIGTERM, Terminated), (signal.SIGINT, KeyboardInterrupt))}
  collecting, unraisable = gc.isenabled(), sys.unraisablehook
  silenced = logging.root.manager.disable
  _open.append(True)
  try:
    yield
  finally:
    _open.clear()
    sys.unraisablehook = unraisable
    logging.disable(silenced)
    if collecting:
      gc.enable()
    for sig, handler in previous.items():  # (None: set outside Python, cannot be set back)
      signal.signal(sig, signal.SIG_DFL if handler is None else handler)
    reset()
