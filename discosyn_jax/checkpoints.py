"""Checkpoints of the whole TrainState (parameters, every optimiser state, normalisers, env
states, rng, step) with orbax, which writes to a temporary folder and renames it when
complete, so a crash never leaves a half-written checkpoint behind.

A run directory holds:
  config.json           the TrainConfig
  checkpoints/<step>/   periodic checkpoints (the newest `keep_checkpoints` kept)
  final/                the state at the end of the run
  metrics.jsonl, eval.jsonl
"""

from __future__ import annotations

import pathlib

import jax
import orbax.checkpoint as ocp

FINAL = "final"
_ITEM = "default"  # CheckpointManager's folder for the one item of a step


def _manager(run_dir: pathlib.Path, keep: int) -> ocp.CheckpointManager:
  options = ocp.CheckpointManagerOptions(max_to_keep=keep, create=True, cleanup_tmp_directories=True,
                                         enable_async_checkpointing=False)
  return ocp.CheckpointManager((run_dir / "checkpoints").resolve(), options=options)


def _named_leaves(tree) -> list[tuple[str, object]]:
  def name(key):
    for attr in ("name", "key", "idx"):
      if hasattr(key, attr):
        return str(getattr(key, attr))
    return str(key)

  return [(".".join(name(k) for k in path), leaf)
          for path, leaf in jax.tree_util.tree_flatten_with_path(tree)[0]]


def _arrays(tree) -> dict[str, jax.Array]:
  """The state's arrays by path name. Empty arrays (e.g. the sensors of a model without
  any) and Python constants are left out: orbax cannot store the first, and the second
  come from the config."""
  return {name: leaf for name, leaf in _named_leaves(tree)
          if isinstance(leaf, jax.Array) and leaf.size > 0}


def save(run_dir: pathlib.Path, state, keep: int, final: bool = False) -> pathlib.Path:
  """Write `state` as a periodic checkpoint (named by its step) or as `final`."""
  run_dir = pathlib.Path(run_dir)
  step = int(state.step)
  arrays = _arrays(state)
  if final:
    path = run_dir / FINAL
    checkpointer = ocp.StandardCheckpointer()
    # force: a resumed run replaces the final state of the run it continues
    checkpointer.save(path.resolve(), arrays, force=True, custom_metadata={"step": step})
    checkpointer.wait_until_finished()
    return path
  with _manager(run_dir, keep) as manager:
    manager.save(step, args=ocp.args.StandardSave(arrays), force=True)
    manager.wait_until_finished()
  return run_dir / "checkpoints" / str(step)


def latest(run_dir: pathlib.Path) -> pathlib.Path | None:
  """The checkpoint of a run that holds the most train steps (final or periodic)."""
  run_dir = pathlib.Path(run_dir)
  candidates = [(int(p.name), 0, p) for p in (run_dir / "checkpoints").glob("*") if p.name.isdigit()]
  if (run_dir / FINAL).is_dir():
    meta = ocp.StandardCheckpointer().metadata((run_dir / FINAL).resolve())
    candidates.append((int(meta.custom_metadata["step"]), 1, run_dir / FINAL))
  return max(candidates)[2] if candidates else None


def _item(path: pathlib.Path) -> pathlib.Path:
  # a periodic checkpoint: CheckpointManager keeps its item in a subfolder
  return path / _ITEM if (path / _ITEM).is_dir() else path


def read_arrays(path: pathlib.Path, prefix: str) -> dict[str, "np.ndarray"]:
  """The arrays of the checkpoint at `path` whose names start with `prefix` (names with the
  prefix removed), without building the state they belong to: e.g. a run's decoder."""
  import numpy as np

  path = _item(pathlib.Path(path))
  try:
    saved = ocp.StandardCheckpointer().restore(path.resolve())
  except (FileNotFoundError, ValueError, KeyError) as err:
    raise ValueError(f"no readable checkpoint at {path} ({type(err).__name__})") from None
  return {k[len(prefix):]: np.asarray(v) for k, v in saved.items() if k.startswith(prefix)}


def restore(path: pathlib.Path, target):
  """The state saved at `path`, in the structure of `target` (a state of the same config).

  A checkpoint written for another config raises ValueError with one line saying so.
  """
  path = _item(pathlib.Path(path))
  checkpointer = ocp.StandardCheckpointer()
  try:
    saved = checkpointer.metadata(path.resolve()).item_metadata
  except (FileNotFoundError, ValueError, KeyError, AttributeError) as err:
    raise ValueError(f"no readable checkpoint at {path} ({type(err).__name__})") from None
  if saved is None:
    raise ValueError(f"no readable checkpoint at {path}")
  wanted = _arrays(target)
  for name in sorted(set(saved) | set(wanted)):
    have = (tuple(saved[name].shape), saved[name].dtype) if name in saved else "absent"
    want = (tuple(wanted[name].shape), wanted[name].dtype) if name in wanted else "absent"
    if have != want:
      raise ValueError(f"checkpoint {path} does not match this config: {name} is {have} there, "
                       f"{want} here")
  abstract = {k: ocp.utils.to_shape_dtype_struct(v) for k, v in wanted.items()}
  restored = checkpointer.restore(path.resolve(), abstract)
  leaves = [restored.get(name, leaf) for name, leaf in _named_leaves(target)]
  return jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(target), leaves)
