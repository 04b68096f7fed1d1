"""A Ctrl-C or SIGTERM that lands inside a garbage-collector callback (JAX registers one,
where Python would print the exception and drop it) is parked and raised by the training
loop's next step (discosyn_jax/run/stop.py); anywhere else it stops the command at once, and
whatever error it causes (a jitted computation it aborted from inside a host callback) is
taken for it; a second signal while it is under way is ignored. (tests/test_faults.py
lands them inside the physics callback of a real run.)"""

import gc
import logging
import signal
import sys

import pytest

from discosyn_jax.run import stop


@pytest.fixture(autouse=True)
def _as_main_leaves_it():
  """What the handler turns off for the run's end, set back as stop.handled does."""
  yield
  gc.enable()
  sys.unraisablehook = sys.__unraisablehook__
  logging.disable(logging.NOTSET)
  stop.reset()


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
  handler = stop.stopper(stop.Terminated)
  handler(signal.SIGTERM, frame)  # parked, not raised
  with pytest.raises(stop.Terminated):
    stop.check()
  stop.check()  # raised once


def test_a_stop_elsewhere_is_raised_at_once():
  assert not stop.in_gc_callback(sys._getframe())
  with pytest.raises(KeyboardInterrupt):
    stop.stopper(KeyboardInterrupt)(signal.SIGINT, sys._getframe())


def test_a_stop_raised_is_under_way_a_second_is_ignored_and_what_follows_is_taken_for_it():
  with pytest.raises(stop.Terminated) as first:
    stop.stopper(stop.Terminated)(signal.SIGTERM, sys._getframe())
  assert stop.under_way()
  stop.stopper(KeyboardInterrupt)(signal.SIGINT, sys._getframe())  # pressed again: ignored
  # what the stop caused (a computation it aborted from inside a host callback) is the stop
  assert stop.taken(RuntimeError("INTERNAL: CpuCallback error")) is first.value
  interrupt = KeyboardInterrupt()
  assert stop.taken(interrupt) is interrupt
  stop.reset()
  assert not stop.under_way() and stop.taken(RuntimeError()) is None


def test_handled_sets_the_stoppers_inside_the_block_and_everything_back_after_it():
  before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
  with stop.handled():
    inside = {sig: signal.getsignal(sig) for sig in before}
    assert all(inside[sig] is not before[sig] for sig in before)
    with stop.handled():  # an inner block (the training loop inside the command) keeps them
      assert {sig: signal.getsignal(sig) for sig in before} == inside
    with pytest.raises(stop.Terminated):
      inside[signal.SIGTERM](signal.SIGTERM, sys._getframe())
    assert stop.under_way() and not gc.isenabled()  # quiet while the stop ends the run
  assert {sig: signal.getsignal(sig) for sig in before} == before
  assert not stop.under_way() and gc.isenabled() and logging.root.manager.disable == logging.NOTSET
