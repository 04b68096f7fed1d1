"""Pictures of a trained synergy decoder (`discosyn synergies RUN`).

- postures.png: the hand at z = -k, 0, +k along each synergy dimension, the others at 0
  (the paper's Fig. 1a). The action is the decoder's mean D(z), clipped to [-1, 1] as the
  env does, held as the position targets of the hand alone (the scene "hand": no object,
  so the picture shows what the decoder asks for, the same for every task) and simulated
  until the joints stop moving.
- matrix.png (linear decoders): the b x actions matrix W of a = W z + c as a heat map, one
  column per actuator, named as in the hand's file. Both on the run's own hand.
"""

from __future__ import annotations

import math
import pathlib

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from discosyn_jax.agent.networks import DiscoSyn  # noqa: E402
from discosyn_jax.checks import BadInput  # noqa: E402
from discosyn_jax.env import hands, scene
from discosyn_jax.viz import render  # noqa: E402

POSTURES_FILE = "postures.png"
MATRIX_FILE = "matrix.png"


def hand_model(hand: str = hands.DEFAULT) -> mujoco.MjModel:
  return scene.load_spec("hand", hand).compile()


def _z_grid(b: int, k: float) -> np.ndarray:
  """(3 b, b): z = -k e_i, 0, +k e_i for each synergy i."""
  return np.einsum("c,ij->icj", np.array([-k, 0.0, k]), np.eye(b)).reshape(3 * b, b).astype(np.float32)


def decoded_actions(trainer, params, k: float) -> np.ndarray:
  """(b, 3, actions) decoder means at z = -k e_i, 0, +k e_i, clipped to the action box."""
  b = trainer.model.n_synergies
  mean, _ = trainer.model.apply(params, _z_grid(b, k), method=DiscoSyn.decode)
  return np.clip(np.asarray(mean), -1.0, 1.0).reshape(b, 3, -1)


def file_postures(synergies, path: pathlib.Path, k: float = 1.0, height: int = 240,
                  width: int = 320) -> pathlib.Path:
  """postures.png of a synergy file (artefact.Synergies): its hand along each synergy."""
  actions = np.clip(synergies.decode(_z_grid(synergies.b, k)), -1.0, 1.0).reshape(synergies.b, 3, -1)
  images = posture_images(actions, height, width, synergies.hand or hands.DEFAULT)
  plot_postures(images, k, pathlib.Path(path),
                f"{synergies.name}: hand at z = -k, 0, +k")
  return pathlib.Path(path)


def settle(model: mujoco.MjModel, action: np.ndarray, max_steps: int = 2000,
           tol: float = 1e-3) -> mujoco.MjData:
  """The hand holding `action` (in [-1, 1] per actuator, mapped to the actuators' ranges as the env
  maps it) after the joints have stopped moving (|qvel| < tol) or `max_steps` steps."""
  data = mujoco.MjData(model)
  lo, hi = model.actuator_ctrlrange.T
  data.ctrl[:] = (hi + lo) / 2 + np.clip(action, -1.0, 1.0) * (hi - lo) / 2
  for _ in range(max_steps // 50):
    mujoco.mj_step(model, data, nstep=50)
    if np.abs(data.qvel).max() < tol:
      break
  mujoco.mj_forward(model, data)
  return data


def posture_images(actions: np.ndarray, height: int, width: int,
                   hand: str = hands.DEFAULT) -> np.ndarray:
  """(b, 3, height, width, 3) front views of the settled `hand` for `decoded_actions`."""
  model = hand_model(hand)
  flat = actions.reshape(-1, actions.shape[-1])
  images = render.many_frames(model, (settle(model, a) for a in flat), ("front",), height, width)
  return np.stack(list(images)).reshape(actions.shape[:2] + (height, width, 3))


def plot_postures(images: np.ndarray, k: float, path: pathlib.Path, title: str) -> None:
  b = images.shape[0]
  fig, axes = plt.subplots(b, 3, figsize=(9, 2.4 * b + 0.5), squeeze=False)
  for i in range(b):
    for j, zi in enumerate((-k, 0.0, k)):
      ax = axes[i, j]
      ax.imshow(images[i, j])
      ax.set_xticks([])
      ax.set_yticks([])
      ax.set_title(f"z{i + 1} = {zi:+g}", fontsize=9)
    axes[i, 0].set_ylabel(f"synergy {i + 1}")
  fig.suptitle(title, fontsize=10)
  fig.tight_layout()
  fig.savefig(path, dpi=80)
  plt.close(fig)


def plot_matrix(kernel: np.ndarray, actuators: list[str], path: pathlib.Path, title: str) -> None:
  """Heat map of the (b, actions) synergy matrix, symmetric colours around 0."""
  b = kernel.shape[0]
  vmax = float(np.abs(kernel).max()) or 1.0
  fig, ax = plt.subplots(figsize=(9, 1.2 + 0.45 * b))
  image = ax.imshow(kernel, cmap="RdBu_r", vmin=-vmax, vmax=vmax, aspect="auto")
  ax.set_xticks(range(len(actuators)), actuators, rotation=90, fontsize=8)
  ax.set_yticks(range(b), [f"synergy {i + 1}" for i in range(b)], fontsize=8)
  fig.colorbar(image, ax=ax, label="action per unit z")
  ax.set_title(title, fontsize=10)
  fig.tight_layout()
  fig.savefig(path, dpi=100)
  plt.close(fig)


def write(trainer, params, out_dir: pathlib.Path, *, k: float = 1.0, force: bool = False,
          height: int = 240, width: int = 320, title: str = "") -> list[pathlib.Path]:
  """Write postures.png (and matrix.png for a linear decoder) into `out_dir`."""
  decoder, kind = trainer.config.decoder, trainer.config.kind
  if kind.full_action:
    raise BadInput(f"this run's decoder is {decoder!r} (the full action): it has no synergies "
                   "to picture")
  if not 0 < k < math.inf:  # NaN too
    raise BadInput(f"--k must be a positive finite number, not {k}")
  out_dir = pathlib.Path(out_dir)
  paths = [out_dir / POSTURES_FILE] + ([out_dir / MATRIX_FILE] if kind.linear else [])
  render.check_new(paths, force)
  out_dir.mkdir(parents=True, exist_ok=True)
  hand = trainer.config.hand
  images = posture_images(decoded_actions(trainer, params, k), height, width, hand)
  plot_postures(images, k, paths[0], f"{title} {decoder} decoder: hand at z = -k, 0, +k".strip())
  if kind.linear:
    kernel = np.asarray(params["params"]["synergy_decoder"]["synergies"]["kernel"])
    plot_matrix(kernel, hands.actuator_names(hand_model(hand)), paths[1], f"{title} synergy matrix W (a = W z + c)".strip())
  return paths
