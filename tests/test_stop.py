"""A Ctrl-C or SIGTERM stops the command where it lands; where Python drops the exception
(a garbage-collector callback, a finalizer) the training loop's next step raises it again
(discosyn_jax/run/stop.py); whatever error it causes (a jitted computation it aborted from
inside a host callback) is taken for it; a second signal while it is under way is ignored.
(tests/test_faults.py lands them inside the physics callback and a finalizer of real runs.)"""

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


def test_a_stop_dropped_inside_a_gc_callback_is_raised_again_at_every_check():
  handler = stop.stopper(stop.Terminated)

  def callback(phase, info):
    handler(signal.SIGTERM, sys._getframe())  # raises: Python drops it (the second call: ignored)

  gc.callbacks.append(callback)
  try:
    gc.collect()  # does not raise
  finally:
    gc.callbacks.remove(callback)
  assert stop.under_way()
  with pytest.raises(stop.Terminated) as first:
    stop.check()
  with pytest.raises(stop.Terminated) as again:
    stop.check()
  assert again.value is first.value
  stop.reset()
  stop.check()  # nothing under way


def test_a_stop_elsewhere_is_raised_at_once():
  stop.check()
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
