"""Why is the reward prior frozen weak at b = 4 on set #1 (Prior4-L-reward)? Two variants of
it, 3 seeds each, beside Table I's rows (docs/notes/2026-12-04-a-prior4.md, "Why Prior4-L-reward is
weak").

  python docs/results/prior4-variants/prior4_variants.py gains        # no training
  python docs/results/prior4-variants/prior4_variants.py train OUT    # 6 set-#1 runs

gains: how the prior's start spreads each seed's random singular values over the prior's
directions (physics_prior.start takes the left singular vectors of the prior's orthonormal
basis, a degenerate SVD: LAPACK's rotation decides which direction gets the largest).
train: Prior4-L-reward with its singular values made equal (their RMS: every prior direction
the same reach; its decoders are decoders/), and Prior4-L-reward with z free.
"""

import pathlib
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[2]
sys.path.insert(0, str(ROOT))

import tasks  # noqa: E402
from discosyn_jax import config as config_lib  # noqa: E402
from discosyn_jax.synergies import fitting, physics_prior  # noqa: E402
from discosyn_jax.training import loop  # noqa: E402

TABLE1 = ROOT / "docs" / "results" / "paper"
SEEDS = (0, 1, 2)


def gains() -> None:
  metrics = [physics_prior.metric(tasks.make(name), "reward") for name in tasks.TASK_SETS["set1"]]
  basis = physics_prior.pool(metrics, 4, "share")  # b = 3's directions are its first three
  for i, m in enumerate(metrics):
    print(f"valve{i}: the prior's share of its metric, b = 3 "
          f"{physics_prior.captured(basis[:, :3], m):.3f}, b = 4 {physics_prior.captured(basis, m):.3f}")
  for b in (3, 4):
    # as physics_prior.start does it: the basis in float32, its SVD in float64
    u0 = np.linalg.svd(basis[:, :b].astype(np.float32).astype(np.float64), full_matrices=False)[0]
    print(f"b = {b}: the prior's directions (rows) in start's singular directions (columns, "
          f"largest singular value first)\n{np.round(basis[:, :b].T @ u0, 2)}")
    for seed in SEEDS:
      _, params = fitting.read(TABLE1 / f"prior{b}-l-reward-set1-seed{seed}" / "decoder.npz")
      kernel = np.asarray(params["synergies"]["kernel"])  # (b, actions)
      reach = np.linalg.norm(kernel @ basis[:, :b], axis=0)  # z's box along each direction
      print(f"  seed {seed}: singular values {np.round(np.linalg.svd(kernel, compute_uv=False), 2)}, "
            f"reach along each prior direction {np.round(reach, 2)}")


def equal_decoder(seed: int) -> pathlib.Path:
  """Prior4-L-reward's frozen decoder of `seed` with its singular values set to their RMS."""
  path = HERE / "decoders" / f"prior4-equal-seed{seed}.npz"
  if not path.is_file():
    meta, params = fitting.read(TABLE1 / f"prior4-l-reward-set1-seed{seed}" / "decoder.npz")
    u, s, vt = np.linalg.svd(np.asarray(params["synergies"]["kernel"], np.float64).T,
                             full_matrices=False)
    params["synergies"]["kernel"] = ((u * np.sqrt(np.mean(s ** 2))) @ vt).T.astype(np.float32)
    fitting.save(path, params, meta)
  return path


def train(out: pathlib.Path) -> None:
  for seed in SEEDS:
    base = config_lib.load(TABLE1 / f"prior4-l-reward-set1-seed{seed}" / "config.json")
    variants = {
        "prior4-equal": base.replace(decoder_init="random", decoder_from=str(equal_decoder(seed))),
        "prior4-l-reward-zfree": base.replace(squash_z=False)}
    for name, config in variants.items():
      loop.train(config.validate(), out / f"{name}-set1-seed{seed}", make_trainer=tasks.trainer,
                 progress=False, log=print)


if __name__ == "__main__":
  if sys.argv[1:2] == ["gains"]:
    gains()
  elif sys.argv[1:2] == ["train"] and len(sys.argv) == 3:
    train(pathlib.Path(sys.argv[2]))
  else:
    print("usage: prior4_variants.py gains | train OUT", file=sys.stderr)
    sys.exit(2)
