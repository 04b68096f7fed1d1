"""Small shared pieces of the tests."""

import functools
import os
import struct

import jax
import jax.numpy as jnp
import numpy as np
from tensorboardX.proto import event_pb2

from discosyn_jax import tasks
from discosyn_jax.env.rollouts import run_episode  # noqa: F401  (the tests' episodes)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the checkout


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


@functools.cache
def env(name: str, backend: str = "native", hand: str = "shadow20"):
  """One env per task, backend and hand for the whole session (an MJX env traces its reset
  when it is built). Tests that change a task's settings make their own."""
  return tasks.make(name, backend=backend, hand=hand)


def on_mjx(native_env, mjx_env, state):
  """A state of `native_env` (one env or a batch) with its physics put on MJX: the host
  MjData after MuJoCo C's forward, as the MJX backend takes it (`from_mjdata`). A test that
  starts MJX from here compiles MJX's step only, not its reset too (each about half a minute
  on 2 cores); MJX's reset itself is run by tests/test_backends.py."""
  lead = state.reward.shape
  host = jax.device_get(state.pipeline_state)
  datas = [mjx_env.physics.from_mjdata(
               native_env.physics.to_mjdata(jax.tree.map(lambda x: x[i], host)))
           for i in np.ndindex(lead)]
  pstate = jax.tree.map(lambda *x: jnp.stack(x).reshape(lead + x[0].shape), *datas)
  return state.replace(pipeline_state=pstate)


# one MJX train step, as small as it goes: 2 envs of valve0, 2 steps, one minibatch
ONE_MJX_STEP = dict(squash_z=False, decoder_init="random", tasks=("valve0",), n_synergies=3,
                    decoder="linear", num_envs=2, unroll_length=2, num_minibatches=1,
                    update_epochs=1, steps=1, eval_every=0, eval_envs=2, checkpoint_every=0,
                    backend="mjx")


def assert_one_step_learns(trainer, state):
  """One train step from `state`: finite, counted, and every parameter group moved."""
  before = jax.tree.map(np.asarray, state.params)
  state, metrics = trainer.train_step(state)
  assert int(state.step) == 1 and bool(metrics["finite"])
  moved = jax.tree.leaves(jax.tree.map(lambda a, b: np.abs(np.asarray(a) - b).max(),
                                       state.params, before))
  assert max(moved) > 0


# -- the code blocks of the pages a user follows (tests/test_doc_snippets.py, test_doc_commands.py)
USER_PAGES = ("README.md", "docs/RESULTS.md", "docs/TAKE_HOME.md", "docs/YOUR_TASK.md",
              "docs/YOUR_HAND.md")
# the size of a documented run in a test: the `ci` scale's (seconds, nothing learned)
TINY = dict(num_envs=4, unroll_length=5, num_minibatches=2, update_epochs=1, steps=2,
            eval_every=1, eval_envs=2, closing_episodes=4, checkpoint_every=0)


def doc_blocks(page: str) -> list[tuple[int, str, str, str | None]]:
  """(line, language, code, why not run) of each fenced block of `page`; why not run: the
  text of a `<!-- not run: ... -->` comment on the line above the fence, else None."""
  import re

  text = open(os.path.join(ROOT, page), encoding="utf-8").read()
  found = []
  for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.M | re.S):
    line = text.count("\n", 0, m.start()) + 1
    above = text[:m.start()].rstrip("\n").rsplit("\n", 1)[-1]
    why = re.fullmatch(r"<!-- not run: (.+) -->", above.strip())
    found.append((line, m.group(1), m.group(2), why.group(1) if why else None))
  return found


def doc_folder(tmp_path):
  """A folder to run a page's blocks in, as from the checkout's root: its examples, records,
  hands and studies read in place, and whatever a block writes (runs/, pictures) kept here."""
  for name in ("xml", "studies"):
    (tmp_path / name).symlink_to(os.path.join(ROOT, name))
  docs = tmp_path / "docs"
  docs.mkdir()
  for name in ("examples", "results"):
    (docs / name).symlink_to(os.path.join(ROOT, "docs", name))
  return tmp_path


def damaged(good: bytes, trial: int, rng) -> bytes:
  """`good` cut short at a random point (odd trials) or with 1-4 random bits flipped (even):
  the fuzz of the files users hand us (synergy files, plans)."""
  data = bytearray(good)
  if trial % 2:
    return bytes(data[: rng.randrange(len(data))])
  for _ in range(rng.randint(1, 4)):
    data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
  return bytes(data)
