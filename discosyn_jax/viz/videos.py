"""Videos of a trained policy (`discosyn render RUN --task NAME`).

The episodes are the evaluation's (Trainer.episodes: head mean, decoder mean, the run's
observation normalisers), one after another, each cut at its end; one frame per control
step, so the video plays in real time. MP4 goes through the ffmpeg binary bundled with
imageio-ffmpeg, GIF through Pillow.
"""

from __future__ import annotations

import pathlib
import warnings
from typing import Iterator

import imageio.v2 as imageio
import jax
import mujoco
import numpy as np
from PIL import Image

from discosyn_jax import checks
from discosyn_jax.checks import BadInput
from discosyn_jax.viz import render

FORMATS = (".mp4", ".gif")


def task_index(config, task: str) -> int:
  if task not in config.tasks:
    raise BadInput(f"task {task!r} is not one of this run's tasks: {', '.join(config.tasks)}")
  return config.tasks.index(task)


def episode_states(trainer, state, task: str, episodes: int, seed: int = 0
                   ) -> tuple[list[list[mujoco.MjData]], np.ndarray, np.ndarray]:
  """The MjData of every control step of `episodes` deterministic episodes of `task` (each up
  to its end, with the task's own values drawn in), their returns and successes."""
  n = task_index(trainer.config, task)
  traj, ret, success = trainer.episodes(state.params, state.normalizers, jax.random.PRNGKey(seed),
                                        task=n, episodes=episodes, keep_states=True)
  traj = jax.device_get(traj)
  states = traj["state"]
  env = trainer.envs[n]
  lengths = np.asarray(traj["alive"]).sum(axis=0).astype(int)  # steps up to each end, included
  out = []
  for e in range(episodes):
    datas = []
    for t in range(lengths[e]):
      at = jax.tree.map(lambda x: x[t, e], states)
      data = env.physics.to_mjdata(at.pipeline_state)
      env.task.show(env.mj_model, data, at.info)
      datas.append(data)
    out.append(datas)
  return out, np.asarray(ret), np.asarray(success)


def write_video(frames: Iterator[np.ndarray], path: pathlib.Path, fps: float) -> int:
  """Write `frames` (uint8, H x W x 3) to an MP4 or GIF by the suffix; return the frame count."""
  suffix = pathlib.Path(path).suffix.lower()
  count = 0
  # imageio-ffmpeg runs ffmpeg in a subprocess (a probe when the writer is made, the encoder
  # at the first frame); JAX warns about any fork, here harmlessly (exec follows)
  with warnings.catch_warnings():
    warnings.filterwarnings("ignore", message="os.fork", category=RuntimeWarning)
    if suffix == ".mp4":
      # macro_block_size 8: the default 16 would rescale 360-pixel-high frames
      writer = imageio.get_writer(path, fps=fps, macro_block_size=8)
    else:
      writer = imageio.get_writer(path, duration=1000 / fps, loop=0)
    with writer:
      for frame in frames:
        writer.append_data(frame)
        count += 1
  return count


def render_policy(trainer, state, task: str, out: pathlib.Path, *, episodes: int = 1, seed: int = 0,
                  frame: int | None = None, force: bool = False, height: int = 360,
                  width: int = 480, cameras=("front", "oblique")) -> dict:
  """Write the video (or, with `frame`, the PNG of that control step of the first episode)
  of the deterministic policy on `task`; return what was written and measured."""
  out = pathlib.Path(out)
  wanted = (".png",) if frame is not None else FORMATS
  if out.suffix.lower() not in wanted:
    raise BadInput(f"{out}: the output must end in {' or '.join(wanted)}")
  env = trainer.envs[task_index(trainer.config, task)]
  model = env.mj_model
  # every request checked before the rollout, which takes a while
  render.check_size(model, height, width)
  if frame is not None and not 0 <= frame < env.episode_length:
    raise BadInput(f"--frame must be between 0 and {env.episode_length - 1} (the control steps "
                   f"of an episode), not {frame}")
  checks.seed(seed, "--seed")
  if episodes < 1:
    raise BadInput(f"--episodes must be at least 1, not {episodes}")
  render.check_new([out], force)
  datas, ret, success = episode_states(trainer, state, task, episodes, seed)
  out.parent.mkdir(parents=True, exist_ok=True)
  if frame is not None:
    if frame >= len(datas[0]):
      raise BadInput(f"--frame {frame} is past the end of the episode, which ended after "
                     f"{len(datas[0])} steps")
    Image.fromarray(render.frames(model, datas[0][frame], cameras, height, width)).save(out)
    count = 1
  else:
    all_states = (d for episode in datas for d in episode)
    frames = render.many_frames(model, all_states, cameras, height, width)
    count = write_video(frames, out, fps=1.0 / env.dt)
  return {"path": out, "frames": count, "return": ret.tolist(), "success": success.tolist(),
          "steps": [len(d) for d in datas]}
