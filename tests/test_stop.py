"""A Ctrl-C or SIGTERM that lands inside a garbage-collector callback (JAX registers one,
where Python would print the exception and drop it) is parked and raised by the training
loop's next step (discosyn_jax/stop.py); anywhere else it stops the command at once."""

import gc
import signal
import sys

import pytest

from discosyn import cli
from discosyn_jax import stop


def _frame_inside_a_gc_callback():
  frames = []

  def callback(phase, info):
    if not frames:
      frames.append(sys._getframe())

  gc.callbacks.append(callback)
  try:
    gc.collect()
  finally:
    gc.callbacks.remove(callback)
  return frames[0], callback


def test_a_stop_inside_a_gc_callback_is_parked_and_raised_at_the_next_check(monkeypatch):
  frame, callback = _frame_inside_a_gc_callback()
  monkeypatch.setattr(gc, "callbacks", [callback])  # as while the callback is registered
  assert stop.in_gc_callback(frame)
  handler = cli._stopper(cli.Terminated)
  handler(signal.SIGTERM, frame)  # parked, not raised
  with pytest.raises(cli.Terminated):
    stop.check()
  stop.check()  # raised once


def test_a_stop_elsewhere_is_raised_at_once():
  assert not stop.in_gc_callback(sys._getframe())
  with pytest.raises(KeyboardInterrupt):
    cli._stopper(KeyboardInterrupt)(signal.SIGINT, sys._getframe())
