"""Small shared pieces of the tests."""

import struct

import jax
from tensorboardX.proto import event_pb2

from discosyn_jax.rollouts import run_episode  # noqa: F401  (the tests' episodes)


def uniform_policy(t, key, batch):
  return jax.random.uniform(key, (batch, 20), minval=-1.0, maxval=1.0)


def tensorboard_scalars(folder) -> dict[str, list[tuple[int, float]]]:
  """{tag: [(step, value)]} of the event files in `folder` (TFRecord: length, crc, data, crc)."""
  out = {}
  for path in sorted(folder.glob("events.out.tfevents.*")):
    blob = path.read_bytes()
    at = 0
    while at < len(blob):
      (length,) = struct.unpack("<Q", blob[at:at + 8])
      event = event_pb2.Event.FromString(blob[at + 12:at + 12 + length])
      at += 12 + length + 4
      for value in event.summary.value:
        out.setdefault(value.tag, []).append((event.step, value.simple_value))
  return out
