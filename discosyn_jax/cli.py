"""The `discosyn` command: train, eval, synergies, render, experiment, report, bench, demo,
tasks, render-scenes. Each command imports what it needs when it runs, so that `--help`
answers without JAX."""

from __future__ import annotations

import argparse
import os
import pathlib
import shlex
import signal
import sys
import threading
import time


class UsageError(Exception):
  """Bad input: reported as one line, exit status 2."""


def cmd_tasks(args) -> None:
  import tasks

  print(f"{'task':16s} {'obs':>4s} {'act':>4s}  {'sets':10s} description")
  for name, entry in tasks.REGISTRY.items():
    env = tasks.make(name, backend="native")
    sets = ",".join(tasks.sets_of(name)) or "-"
    print(f"{name:16s} {env.observation_size:4d} {env.action_size:4d}  {sets:10s} {entry.summary}")


def cmd_demo(args) -> None:
  """Build each scene, run a random policy for one episode per env, print what it measured."""
  import jax

  import tasks

  print(f"random policy, {args.batch} envs x one episode per task")
  print(f"{'task':8s} {'backend':7s} {'obs':>4s} {'build s':>8s} {'compile s':>9s} {'env steps/s':>11s} "
        f"{'return':>7s} {'success':>7s} {'diverged':>8s}")
  for name in tasks.expand(args.tasks):
    start = time.perf_counter()
    env = tasks.make(name, backend=args.backend)
    built = time.perf_counter() - start

    def episode(keys):
      state = jax.vmap(env.reset)(keys)

      def body(carry, key):
        state, ret = carry
        action = jax.random.uniform(key, (keys.shape[0], env.action_size), minval=-1, maxval=1)
        state = jax.vmap(env.step)(state, action)
        return (state, ret + state.reward), state.metrics["diverged"]

      steps = jax.random.split(jax.random.PRNGKey(args.seed + 1), env.episode_length)
      (state, ret), diverged = jax.lax.scan(body, (state, jax.numpy.zeros(keys.shape[0])), steps)
      return state, ret, diverged.sum()

    run = jax.jit(episode)
    keys = jax.random.split(jax.random.PRNGKey(args.seed), args.batch)
    start = time.perf_counter()
    run = run.lower(keys).compile()
    compiled = time.perf_counter() - start
    start = time.perf_counter()
    state, ret, diverged = jax.block_until_ready(run(keys))
    rate = args.batch * env.episode_length / (time.perf_counter() - start)
    print(f"{name:8s} {env.backend:7s} {env.observation_size:4d} {built:8.2f} {compiled:9.2f} {rate:11,.0f} "
          f"{float(ret.mean()):7.2f} {float(state.metrics['success'].mean()):7.1%} {int(diverged):8d}")


def cmd_render_scenes(args) -> None:
  import jax
  import jax.numpy as jnp
  from PIL import Image

  import tasks
  from discosyn_jax import render, scripted

  out = pathlib.Path(args.out)
  names = tasks.expand(args.tasks)  # a bad name fails before the folder is made
  out.mkdir(parents=True, exist_ok=True)
  for name in names:
    env = tasks.make(name, backend="native")
    # a frame from the task's scripted motion (valves: the middle of a stroke, fingers dipped)
    actions = jnp.asarray(scripted.for_task(name, args.step, env.dt))
    state = env.reset(jax.random.PRNGKey(args.seed))
    for action in actions:
      state = env.step(state, action)
    data = env.physics.to_mjdata(jax.device_get(state.pipeline_state))
    env.task.show(env.mj_model, data, jax.device_get(state.info))
    path = out / f"{name}.png"
    Image.fromarray(render.frames(env.mj_model, data)).save(path)
    print(path)


# train flags -> TrainConfig fields; a flag left out keeps the preset's value
_TRAIN_FLAGS = {
    "synergies": "n_synergies", "decoder": "decoder", "alpha1": "alpha1", "alpha2": "alpha2",
    "alpha3": "alpha3", "num_envs": "num_envs", "unroll_length": "unroll_length",
    "minibatches": "num_minibatches", "epochs": "update_epochs", "lr": "learning_rate",
    "steps": "steps", "seed": "seed", "backend": "backend", "physics": "physics",
    "eval_every": "eval_every",
    "eval_envs": "eval_envs", "checkpoint_every": "checkpoint_every",
    "decoder_weight_decay": "decoder_weight_decay",
    "decoder_weight_decay_steps": "decoder_weight_decay_steps",
}


def train_config(args, base=None):
  """The preset (or, when resuming, the run's own config) with the flags given applied."""
  import tasks
  from experiments import presets

  if base is None or args.preset is not None:
    base = presets.preset("quickstart" if args.preset is None else args.preset)
  changes = {field: getattr(args, flag) for flag, field in _TRAIN_FLAGS.items()
             if getattr(args, flag) is not None}
  if args.tasks:
    changes["tasks"] = tuple(tasks.expand(args.tasks))
  if args.decoder_from:
    from discosyn_jax import synergies

    meta, _ = synergies.read(args.decoder_from)
    frozen = synergies.frozen_fields(meta, args.decoder_from)
    changes = {**frozen, **changes}  # flags given explicitly win (e.g. --alpha2)
    if changes["decoder"] != frozen["decoder"] or changes["n_synergies"] != frozen["n_synergies"]:
      raise UsageError(f"--decoder-from {args.decoder_from} holds a {frozen['decoder']} decoder "
                       f"with {frozen['n_synergies']} synergies; drop --decoder / --synergies")
  return base.replace(**changes).validate()


def cmd_train(args) -> None:
  from discosyn_jax import config as config_lib
  from discosyn_jax import devices, loop, runs

  if args.out == "":
    raise UsageError("--out is empty: name a run directory (or leave --out out)")
  out = pathlib.Path(args.out or f"runs/{args.preset or 'quickstart'}-seed{args.seed or 0}")
  saved = out / loop.CONFIG_FILE
  if args.resume and saved.is_file():  # the run's own config: what a dead writer left settled
    runs.take_over(out)
  base = config_lib.load(saved) if args.resume and saved.is_file() else None
  config = train_config(args, base)
  devices.mesh_for(config, args.devices)  # a bad device count fails before the run directory
  if args.stop_at is not None and not 0 <= args.stop_at <= 1:
    raise ValueError(f"--stop-at is a success rate in [0, 1], not {args.stop_at}")
  print(f"run directory: {out}")
  done = loop.train(config, out, resume=args.resume, force=args.force,
                    progress=not args.no_progress, devices=args.devices, stop_at=args.stop_at)
  print(next_commands(out, done["state"].step, config, done["results"]))


def next_commands(out: pathlib.Path, step, config, results) -> str:
  """What to do with a finished run, its folder filled in."""
  run = shlex.quote(str(out))
  best = max(config.tasks, key=lambda t: results[t]["success"])
  lines = ["next:"]
  if config.decoder != "identity":
    lines.append(f"  discosyn synergies {run}                 # the hand along each synergy")
  lines += [f"  discosyn render {run} --task {best}    # a video of the policy on {best}",
            f"  discosyn eval {run}                      # evaluate the run again",
            f"  discosyn train --out {run} --resume --steps {2 * int(step)}   # train for longer"]
  return "\n".join(lines)


def cmd_eval(args) -> None:
  import jax

  from discosyn_jax import loop

  changes = {"backend": args.backend} if args.backend else {}
  if args.episodes is not None:
    changes["eval_envs"] = args.episodes
  trainer, state = loop.load_trained(args.run, **changes)
  results = loop.evaluate(trainer, state)
  print(loop.format_table(results, int(jax.device_get(state.step)), trainer.config))


def _derived_name(path, run_dir: pathlib.Path, name: str, step: int) -> str:
  """`name` for the pictures of a run's latest state, `name-step<N>` for one checkpoint's."""
  return name if pathlib.Path(path).resolve() == run_dir.resolve() else f"{name}-step{step}"


def cmd_synergies(args) -> None:
  from discosyn_jax import loop, synergy_pictures

  run_dir = loop.find_run_dir(args.run)
  trainer, state = loop.load_trained(args.run, backend="native")  # host physics: pictures only
  step = int(state.step)
  default = run_dir / _derived_name(args.run, run_dir, "synergies", step)
  out = pathlib.Path(args.out) if args.out else default
  paths = synergy_pictures.write(trainer, state.params, out, k=args.k, force=args.force,
                                 title=f"{run_dir.resolve().name} step {step}:")
  for path in paths:
    print(path)


def cmd_render(args) -> None:
  from discosyn_jax import loop, videos

  run_dir = loop.find_run_dir(args.run)
  trainer, state = loop.load_trained(args.run, backend="native")
  videos.task_index(trainer.config, args.task)  # a bad task fails before any rollout
  name = _derived_name(args.run, run_dir, args.task, int(state.step))
  suffix = ".mp4" if args.frame is None else f"-frame{args.frame}.png"
  out = pathlib.Path(args.out) if args.out else run_dir / "videos" / f"{name}{suffix}"
  written = videos.render_policy(trainer, state, args.task, out, episodes=args.episodes,
                                 seed=args.seed, frame=args.frame, force=args.force,
                                 height=args.height, width=args.width,
                                 cameras=tuple(args.camera or ("front", "oblique")))
  for steps, ret, success in zip(written["steps"], written["return"], written["success"]):
    print(f"episode: {steps} steps, return {ret:.2f}, success {success:.0f}")
  print(f"{written['path']} ({written['frames']} frames)")


def cmd_experiment(args) -> None:
  from experiments import paper

  out = pathlib.Path(args.out)
  seeds = tuple(args.seeds) if args.seeds else getattr(paper.SCALES.get(args.scale), "seeds", (0,))
  only = f", methods {' '.join(args.methods)}" if args.methods else ""
  print(f"experiment {args.name} at scale {args.scale}, seeds {' '.join(map(str, seeds))}{only}, "
        f"in {out}")
  start = time.perf_counter()
  paper.run(args.name, out, args.scale, seeds, decoder_from=args.decoder_from,
            methods=args.methods, progress=args.progress)
  print(f"experiment {args.name} finished in {(time.perf_counter() - start) / 60:.1f} min")


def cmd_upgrade(args) -> None:
  from discosyn_jax import config as config_lib
  from discosyn_jax import loop, runs

  for run in map(pathlib.Path, args.runs):
    runs.refuse_if_written(run)
    added = config_lib.upgrade(loop.find_run_dir(run) / loop.CONFIG_FILE)
    print(f"{run}: {'added ' + ', '.join(added) if added else 'up to date'}")


def cmd_report(args) -> None:
  from discosyn_jax import report

  path = report.write(args.runs, pathlib.Path(args.out), threshold=args.threshold,
                      with_tsne=not args.no_tsne, force=args.force)
  print(path)


def build_parser() -> argparse.ArgumentParser:
  from experiments import presets  # TrainConfig only, no JAX

  parser = argparse.ArgumentParser(prog="discosyn", description=__doc__)
  sub = parser.add_subparsers(dest="command", required=True)
  quick = presets.PRESETS["quickstart"]

  def preset_default(field: str, what: str = "") -> str:
    value = getattr(quick, field)
    value = " ".join(value) if isinstance(value, tuple) else value
    return f"default: the preset's; quickstart's is {value}{what}"

  p = sub.add_parser("train", help="train synergies and policies (a preset, flags replace fields)")
  p.add_argument("--preset", help="a named config of experiments/presets.py: "
                 f"{', '.join(presets.PRESETS)} (default: quickstart; with --resume: the run's "
                 "own)")
  p.add_argument("--tasks", nargs="+", help="tasks or task sets, e.g. set1 valve_cw (`discosyn "
                 "tasks` lists them); " + preset_default("tasks"))
  p.add_argument("--synergies", type=int, help="synergy count b, the size of z (1-20); "
                 + preset_default("n_synergies"))
  p.add_argument("--decoder", help="linear | mlp | identity (full-action PPO); "
                 + preset_default("decoder"))
  p.add_argument("--alpha1", type=float, help="weight of the entropy bonus H(pi(z|s,n)) in the "
                 "loss (paper Eq. 2); " + preset_default("alpha1"))
  p.add_argument("--alpha2", type=float, help="weight of the discriminator reward log q(z|a), "
                 "added to the reward of every control step; " + preset_default("alpha2"))
  p.add_argument("--alpha3", type=float, help="weight of the decoder entropy bonus H(p(a|z)) in "
                 "the loss; " + preset_default("alpha3"))
  p.add_argument("--decoder-weight-decay", type=float, help="AdamW weight decay of the decoder's "
                 "weights, a tie-breaker between adequate synergy spaces (issue 26; 0: the paper's "
                 "update); " + preset_default("decoder_weight_decay"))
  p.add_argument("--decoder-weight-decay-steps", type=int, help="the decay falls linearly to "
                 "nothing over this many train steps (0: constant); "
                 + preset_default("decoder_weight_decay_steps"))
  p.add_argument("--lr", type=float, help="Adam learning rate of the policy, value and decoder "
                 "networks; " + preset_default("learning_rate"))
  p.add_argument("--num-envs", type=int, help="parallel envs per task; "
                 + preset_default("num_envs", " envs"))
  p.add_argument("--unroll-length", type=int, help="control steps every env takes per train step; "
                 + preset_default("unroll_length", " steps"))
  p.add_argument("--minibatches", type=int, help="minibatches per PPO epoch; "
                 + preset_default("num_minibatches"))
  p.add_argument("--epochs", type=int, help="PPO epochs over each train step's samples; "
                 + preset_default("update_epochs"))
  p.add_argument("--steps", type=int, help="train steps in all (a resumed run counts those done); "
                 "one train step is tasks x num-envs x unroll-length env (control) steps, "
                 f"quickstart's {quick.env_steps_per_train_step:,}; " + preset_default("steps"))
  p.add_argument("--seed", type=int, help="seed of the initial networks, initial states and "
                 "training noise; " + preset_default("seed"))
  p.add_argument("--eval-every", type=int, help="train steps between deterministic evaluations, "
                 "0: only at the end; " + preset_default("eval_every", " train steps"))
  p.add_argument("--eval-envs", type=int, help="episodes per task in an evaluation; "
                 + preset_default("eval_envs", " episodes"))
  p.add_argument("--checkpoint-every", type=int, help="train steps between checkpoints, 0: only "
                 "the final one; " + preset_default("checkpoint_every", " train steps"))
  p.add_argument("--backend", choices=["auto", "native", "mjx"], help="physics: native (MuJoCo C, "
                 "CPU), mjx, or auto (native on a CPU, mjx on an accelerator); "
                 + preset_default("backend"))
  p.add_argument("--physics", choices=["fast", "reference"], help="the tasks' physics: fast "
                 "(each task's cheapest faithful setting) or reference (4 ms x 10 substeps, the "
                 "runs before 2026-12-02); docs/BENCHMARKS.md, 'Physics settings'; "
                 + preset_default("physics"))
  p.add_argument("--decoder-from", help="learn in the frozen synergy space of a run folder or a "
                 "synergy file (.npz): its decoder, no discriminator bonus or decoder entropy "
                 "(default: none, the decoder is learned)")
  p.add_argument("--stop-at", type=float, help="end the run at the first evaluation at which "
                 "every task's deterministic success is at least this, 0-1 (default: run all "
                 "--steps)")
  p.add_argument("--out", help="run directory (default: runs/<preset>-seed<seed>)")
  p.add_argument("--resume", action="store_true", help="continue the run in --out")
  p.add_argument("--force", action="store_true", help="replace the run in --out")
  p.add_argument("--no-progress", action="store_true", help="no progress bar (it is a line every "
                 "tenth of the run when stderr is not a terminal)")
  add_device_flags(p)
  p.set_defaults(fn=cmd_train)

  p = sub.add_parser("eval", help="evaluate a run (its latest checkpoint) or one checkpoint")
  p.add_argument("run", help="a run directory or a checkpoint folder in one")
  p.add_argument("--episodes", type=int, help="episodes per task (default: the run's eval_envs)")
  p.add_argument("--backend", choices=["auto", "native", "mjx"],
                 help="physics backend (default: the run's)")
  p.set_defaults(fn=cmd_eval)

  p = sub.add_parser("synergies", help="pictures of a run's synergies: the hand along each "
                     "synergy, and the matrix of a linear decoder (needs EGL or OSMesa)")
  p.add_argument("run", help="a run directory or a checkpoint folder in one")
  p.add_argument("--out", help="folder for postures.png and matrix.png (default: RUN/synergies)")
  p.add_argument("--k", type=float, default=1.0, help="the hand is shown at z = -k, 0, +k "
                 "(in units of z, whose prior is a unit normal; default: %(default)s)")
  p.add_argument("--force", action="store_true", help="replace pictures already there")
  p.set_defaults(fn=cmd_synergies)

  p = sub.add_parser("render", help="a video (MP4 or GIF) of a run's deterministic policy on a "
                     "task (needs EGL or OSMesa)")
  p.add_argument("run", help="a run directory or a checkpoint folder in one")
  p.add_argument("--task", required=True, help="one of the run's tasks")
  p.add_argument("--out", help="an .mp4 or .gif file, a .png with --frame (default: "
                 "RUN/videos/TASK.mp4, TASK-frameN.png)")
  p.add_argument("--episodes", type=int, default=1, help="episodes, one after another (default: %(default)s)")
  p.add_argument("--frame", type=int, help="write only this control step of the first episode "
                 "as a PNG (default: none, the whole video)")
  p.add_argument("--seed", type=int, default=0, help="draws the episodes' initial states "
                 "(default: %(default)s)")
  p.add_argument("--camera", action="append", choices=["front", "oblique"],
                 help="a view, side by side when repeated (default: front and oblique)")
  p.add_argument("--height", type=int, default=360, help="pixels per view (at most 480; default: %(default)s)")
  p.add_argument("--width", type=int, default=480, help="pixels per view (at most 640; default: %(default)s)")
  p.add_argument("--force", action="store_true", help="replace the file if it exists")
  p.set_defaults(fn=cmd_render)

  p = sub.add_parser("experiment", help="run one of the paper's experiments, or all, at a scale "
                     "(experiments/paper.py); finished steps are kept, unfinished ones resumed")
  p.add_argument("name", help="discosyn-set1 | discosyn-set2 | baselines-set1 | baselines-set2 | "
                 "transfer | sparse | all; the planted-synergy test bed: discosyn-planted | "
                 "discosyn-planted_slack")
  p.add_argument("--scale", default="cpu", help="ci (seconds per run) | cpu (minutes per run on "
                 "2 cores) | gpu (one accelerator); default: %(default)s")
  p.add_argument("--seeds", type=int, nargs="+",
                 help="training seeds: every step runs once per seed (default: the scale's, "
                 "0 1 2 for cpu and gpu, 0 for ci)")
  p.add_argument("--out", default="runs/experiments",
                 help="folder of the experiment's runs (default: %(default)s)")
  p.add_argument("--decoder-from", help="transfer / sparse: the frozen decoder of this run folder "
                 "or synergy file, instead of training their own DiscoSyn run first (default: none)")
  p.add_argument("--methods", nargs="+", metavar="METHOD",
                 help="only these methods' runs and the runs they need, e.g. DiscoSyn3-L "
                 "Random3-L, or PCA4 (with its PPO run and fit); default: every method")
  p.add_argument("--progress", action="store_true", help="a progress bar per run")
  p.set_defaults(fn=cmd_experiment)

  p = sub.add_parser("report", help="REPORT.md and figures from run folders: solved tasks, "
                     "explained variance, curves, t-SNE, transfer, sparse reward")
  p.add_argument("runs", nargs="+", help="run folders, synergy-fit folders, or folders of them")
  p.add_argument("--out", default="report",
                 help="folder for REPORT.md and its figures (default: %(default)s)")
  p.add_argument("--threshold", type=float, default=0.8,
                 help="final success rate (a fraction, 0-1) at or above which a task counts as "
                 "solved (default: %(default)s)")
  p.add_argument("--no-tsne", action="store_true", help="skip the t-SNE (it rolls policies out)")
  p.add_argument("--force", action="store_true", help="replace a report already in --out")
  p.set_defaults(fn=cmd_report)

  p = sub.add_parser("upgrade", help="write into the config.json of runs made by an older "
                     "release the fields added since, with the values it ran")
  p.add_argument("runs", nargs="+", help="run directories")
  p.set_defaults(fn=cmd_upgrade)

  p = sub.add_parser("demo", help="build task scenes, step them with random actions, print figures")
  p.add_argument("tasks", nargs="*", default=["set1"], help="tasks or task sets (default: set1)")
  p.add_argument("--backend", default="auto", choices=["auto", "native", "mjx"],
                 help="physics backend (default: %(default)s: native on a CPU, mjx on an "
                 "accelerator)")
  p.add_argument("--batch", type=int, default=16, help="parallel envs per task (default: "
                 "%(default)s)")
  p.add_argument("--seed", type=int, default=0, help="seed of the initial states and actions "
                 "(default: %(default)s)")
  p.set_defaults(fn=cmd_demo)

  p = sub.add_parser("tasks", help="list the tasks with observation size and set membership")
  p.set_defaults(fn=cmd_tasks)

  p = sub.add_parser("render-scenes", help="write a PNG of each task scene (needs EGL or OSMesa)")
  p.add_argument("tasks", nargs="*", default=["set1"], help="tasks or task sets (default: set1)")
  p.add_argument("--out", default="docs/scenes", help="folder for TASK.png (default: %(default)s)")
  p.add_argument("--step", type=int, default=14, help="control steps of the task's scripted motion "
                 "before the picture (default: %(default)s)")
  p.add_argument("--seed", type=int, default=0, help="draws the initial state (default: %(default)s)")
  p.set_defaults(fn=cmd_render_scenes)
  add_bench_parser(sub)
  return parser


def add_device_flags(p) -> None:
  p.add_argument("--devices", type=int, help="devices to split the env batch over (default: all "
                 "of them)")
  p.add_argument("--distributed", action="store_true",
                 help="multi-host: jax.distributed.initialize() first (docs/SCALING.md)")


def add_bench_parser(sub) -> None:
  from experiments import bench

  p = sub.add_parser("bench", help="physics and training env steps/s beside raw MuJoCo C")
  bench.build_parser(p)
  p.set_defaults(fn=bench.run)


class Terminated(KeyboardInterrupt):
  """SIGTERM (a scheduler ending the job): it stops a command as Ctrl-C does."""


def _terminate(signum, frame):
  raise Terminated()


def main(argv: list[str] | None = None) -> int:
  args = build_parser().parse_args(argv)
  # a handler only the main thread may set (a notebook may call main from another)
  main_thread = threading.current_thread() is threading.main_thread()
  previous = signal.signal(signal.SIGTERM, _terminate) if main_thread else None
  try:
    return _run(args)
  except KeyboardInterrupt as err:  # Ctrl-C or SIGTERM: one line (where a run resumes from)
    how, signum = ("SIGTERM", signal.SIGTERM) if isinstance(err, Terminated) else \
        ("Ctrl-C", signal.SIGINT)
    print(f"discosyn: stopped by {how}{': ' + str(err) if str(err) else ''}", file=sys.stderr)
    return 128 + signum
  finally:
    if main_thread:  # (None: a handler set outside Python, which cannot be set back)
      signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)


def exit_with(code: int) -> None:
  """End the process with `code`. A command stopped by Ctrl-C or SIGTERM has already closed
  its files and said where it stopped; it ends at once, without the interpreter's shutdown,
  where orbax's idle writer threads printed "Event loop is closed" tracebacks after that line."""
  if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
  sys.exit(code)


def entry() -> None:
  """The `discosyn` command."""
  exit_with(main())


def _run(args) -> int:
  import discosyn_jax

  if getattr(args, "distributed", False):  # before anything touches a device
    from discosyn_jax import devices

    devices.initialize_distributed()
  discosyn_jax.setup_jax()  # before anything imports MJX (brax, through loop)
  from discosyn_jax.loop import TrainingDiverged
  try:
    if getattr(args, "batch", 1) < 1:
      raise UsageError(f"--batch must be at least 1, not {args.batch}")
    if getattr(args, "seed", None) is not None:
      from discosyn_jax import checks

      checks.seed(args.seed, "--seed")
    args.fn(args)
  except (UsageError, ValueError) as err:
    print(f"discosyn: error: {err}", file=sys.stderr)
    return 2
  except OSError as err:  # a file that cannot be read or written: a path, a full disk
    print(f"discosyn: error: {err.filename + ': ' if err.filename else ''}"
          f"{err.strerror or err}", file=sys.stderr)
    return 2
  except TrainingDiverged as err:  # the run stopped; its checkpoints are kept
    print(f"discosyn: {err}", file=sys.stderr)
    return 1
  return 0


if __name__ == "__main__":
  entry()
