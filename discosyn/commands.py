"""The `discosyn` commands, one function each (`discosyn/cli.py` parses their flags). Each
imports what it needs when it runs, so that `--help` answers without JAX."""

from __future__ import annotations

import pathlib
import shlex
import time

from discosyn_jax.checks import BadInput
from discosyn_jax.run import layout


class UsageError(BadInput):
  """A flag or argument of a command that cannot be used: one line, exit status 2."""


def cmd_tasks(args) -> None:
  from discosyn_jax import tasks
  print(f"{'task':16s} {'obs':>4s} {'act':>4s}  {'sets':10s} description")
  for name, entry in tasks.REGISTRY.items():
    env = tasks.make(name, backend="native")
    sets = ",".join(tasks.sets_of(name)) or "-"
    print(f"{name:16s} {env.observation_size:4d} {env.action_size:4d}  {sets:10s} {entry.summary}")


def cmd_demo(args) -> None:
  """Build each scene, run a random policy for one episode per env, print what it measured;
  and the neutral action's return and success (every actuator at mid-range, where an
  untrained policy's deterministic action starts: a task it nearly solves teaches nothing,
  docs/YOUR_TASK.md)."""
  import jax
  import jax.numpy as jnp

  from discosyn_jax import tasks
  from discosyn_jax.env import rollouts

  names = tasks.expand(args.tasks)
  width = max(8, *(len(tasks.label(name)) for name in names))  # one's own task by its class
  print(f"random policy, {args.batch} envs x one episode per task; neutral: the zero action")
  print(f"{'task':{width}s} {'backend':7s} {'obs':>4s} {'build s':>8s} {'compile s':>9s} {'env steps/s':>11s} "
        f"{'return':>7s} {'success':>7s} {'diverged':>8s} {'neutral: return':>15s} {'success':>7s}")
  for name in names:
    start = time.perf_counter()
    env = tasks.make(name, backend=args.backend, hand=args.hand)
    built = time.perf_counter() - start
    uniform = lambda t, key, batch, env=env: jax.random.uniform(
        key, (batch, env.action_size), minval=-1, maxval=1)
    keys = jax.random.split(jax.random.PRNGKey(args.seed), args.batch)
    start = time.perf_counter()
    run = rollouts.episode_fn(env, uniform, seed=args.seed + 1).lower(keys).compile()
    compiled = time.perf_counter() - start
    start = time.perf_counter()
    _, states = jax.block_until_ready(run(keys))
    rate = args.batch * env.episode_length / (time.perf_counter() - start)
    ret, success = states.reward.sum(0).mean(), states.metrics["success"][-1].mean()
    zero = lambda t, key, batch, env=env: jnp.zeros((batch, env.action_size))
    neutral = rollouts.run_episode(env, keys, zero)[1]
    print(f"{tasks.label(name):{width}s} {env.backend:7s} {env.observation_size:4d} {built:8.2f} {compiled:9.2f} {rate:11,.0f} "
          f"{float(ret):7.2f} {float(success):7.1%} {int(states.metrics['diverged'].sum()):8d} "
          f"{float(neutral.reward.sum(0).mean()):15.2f} {float(neutral.metrics['success'][-1].mean()):7.1%}")


def cmd_render_scenes(args) -> None:
  import jax
  import jax.numpy as jnp
  from PIL import Image

  from discosyn_jax import tasks
  from discosyn_jax.env import hands
  from discosyn_jax.viz import render

  out = pathlib.Path(args.out)
  names = tasks.expand(args.tasks)  # a bad name or hand fails before the folder is made
  hand = hands.load(args.hand)
  if args.step < 0:
    raise UsageError(f"--step must be at least 0, not {args.step}")
  pictures = {}  # every scene first: a failure leaves no folder or half of one
  for name in names:
    env = tasks.make(name, backend="native", hand=hand)
    # a frame from the task's scripted motion (valves: the middle of a stroke, fingers dipped);
    # a hand of one's own has none: its initial pose
    actions = (jnp.asarray(env.task.motion.actions(args.step, env.dt, hand.name))
               if hand.name in hands.SHIPPED else [])
    state = env.reset(jax.random.PRNGKey(args.seed))
    for action in actions:
      state = env.step(state, action)
    data = env.physics.to_mjdata(jax.device_get(state.pipeline_state))
    env.task.show(env.mj_model, data, jax.device_get(state.info))
    pictures[out / f"{tasks.label(name)}.png"] = render.frames(env.mj_model, data)
  out.mkdir(parents=True, exist_ok=True)
  for path, frame in pictures.items():
    Image.fromarray(frame).save(path)
    print(path)


# train flags -> TrainConfig fields (cli.py writes their help from the fields' docs); a flag
# left out keeps the preset's value
TRAIN_FLAGS = {
    "synergies": "n_synergies", "decoder": "decoder", "alpha1": "alpha1", "alpha2": "alpha2",
    "alpha3": "alpha3", "num_envs": "num_envs", "unroll_length": "unroll_length",
    "minibatches": "num_minibatches", "epochs": "update_epochs", "lr": "learning_rate",
    "steps": "steps", "seed": "seed", "backend": "backend", "physics": "physics",
    "eval_every": "eval_every",
    "eval_envs": "eval_envs", "checkpoint_every": "checkpoint_every",
    "decoder_weight_decay": "decoder_weight_decay",
    "decoder_weight_decay_steps": "decoder_weight_decay_steps",
    "decoder_init": "decoder_init", "freeze_decoder": "freeze_decoder", "squash_z": "squash_z",
    "discriminator_target": "discriminator_target", "task_posture": "task_posture",
    "residual": "residual", "residual_ramp": "residual_ramp", "residual_start": "residual_start",
    "closing_episodes": "closing_episodes", "z_std_floor": "z_std_floor",
    "task_noise": "task_noise", "bonus_cap": "bonus_cap", "own_synergies": "own_synergies",
}


def train_config(args, base=None):
  """The preset (or, when resuming, the run's own config) with the flags given applied."""
  from discosyn_jax import tasks
  from discosyn_jax.experiments import presets

  if base is None or args.preset is not None:
    base = presets.preset("quickstart" if args.preset is None else args.preset)
  changes = {field: getattr(args, flag) for flag, field in TRAIN_FLAGS.items()
             if getattr(args, flag) is not None}
  if args.tasks:
    changes["tasks"] = tuple(tasks.expand(args.tasks))
  if args.hand:
    from discosyn_jax.env import hands

    changes["hand"] = hands.load(args.hand).name  # checked before the folder is made
  if args.decoder_from:
    from discosyn_jax.synergies import fitting

    meta, _ = fitting.read(args.decoder_from)
    frozen = fitting.frozen_fields(meta, args.decoder_from)
    changes = {**frozen, **changes}  # flags given explicitly win (e.g. --alpha2)
    if changes["decoder"] != frozen["decoder"] or changes["n_synergies"] != frozen["n_synergies"]:
      raise UsageError(f"--decoder-from {args.decoder_from} holds a {frozen['decoder']} decoder "
                       f"with {frozen['n_synergies']} synergies; drop --decoder / --synergies")
  return base.replace(**changes).validate()


def cmd_train(args) -> None:
  from discosyn_jax import config as config_lib
  from discosyn_jax.run import owner
  from discosyn_jax import assemble
  from discosyn_jax.training import devices

  if args.out == "":
    raise UsageError("--out is empty: name a run directory (or leave --out out)")
  if args.resume and args.force:
    raise UsageError("--resume continues the run in --out and --force replaces it: give one")
  out = pathlib.Path(args.out or f"runs/{args.preset or 'quickstart'}-seed{args.seed or 0}")
  saved = out / layout.CONFIG_FILE
  if args.resume and saved.is_file():  # the run's own config: what a dead writer left settled
    owner.take_over(out)
  base = config_lib.load(saved) if args.resume and saved.is_file() else None
  config = train_config(args, base)
  devices.mesh_for(config, args.devices)  # a bad device count fails before the run directory
  if args.stop_at is not None and not 0 <= args.stop_at <= 1:
    raise UsageError(f"--stop-at is a success rate in [0, 1], not {args.stop_at}")
  print(f"run directory: {out}")
  done = assemble.train(config, out, resume=args.resume, force=args.force,
                        progress=not args.no_progress, stop_at=args.stop_at, devices=args.devices)
  print(next_commands(out, done["state"].step, config, done["results"]))


def next_commands(out: pathlib.Path, step, config, results) -> str:
  """What to do with a finished run, its folder filled in."""
  run = shlex.quote(str(out))
  best = max(config.tasks, key=lambda t: results[t]["success"])
  lines = ["next:"]
  if not config.kind.full_action:
    lines.append(f"  discosyn synergies {run}                 # the hand along each synergy")
  lines += [f"  discosyn render {run} --task {best}    # a video of the policy on {best}",
            f"  discosyn eval {run}                      # evaluate the run again",
            f"  discosyn train --out {run} --resume --steps {2 * int(step)}   # train for longer"]
  return "\n".join(lines)


def cmd_eval(args) -> None:
  import jax

  from discosyn_jax import assemble
  from discosyn_jax.training import evaluation

  changes = {"backend": args.backend} if args.backend else {}
  if args.episodes is not None:
    changes["eval_envs"] = args.episodes
  trainer, state = assemble.load(args.run, **changes)
  results = evaluation.evaluate(trainer, state)
  print(evaluation.format_table(results, int(jax.device_get(state.step)), trainer.config))


def _derived_name(path, run_dir: pathlib.Path, name: str, step: int) -> str:
  """`name` for the pictures of a run's latest state, `name-step<N>` for one checkpoint's."""
  return name if pathlib.Path(path).resolve() == run_dir.resolve() else f"{name}-step{step}"


def _check_scenes(trainer, run, what: str) -> None:
  """Pictures and videos need a MuJoCo scene; the planted test bed's tasks have none."""
  bare = [name for name, env in zip(trainer.config.tasks, trainer.envs)
          if getattr(env, "mj_model", None) is None]
  if bare:
    raise UsageError(f"{run}: {', '.join(bare)} {'has' if len(bare) == 1 else 'have'} no scene to "
                     f"{what} (a pure-JAX task, as the planted test bed's)")


def cmd_synergies(args) -> None:
  from discosyn_jax.run import reading
  from discosyn_jax import assemble
  from discosyn_jax.viz import synergy_pictures

  if args.export is not None:
    from discosyn_jax.synergies import artefact

    if not args.export.strip():
      raise UsageError("--export needs a file name, not an empty one")
    path = pathlib.Path(args.export)
    if path.exists() and not args.force:
      raise UsageError(f"{path} exists; pass --force to replace it")
    from discosyn_jax.experiments import record, report_runs

    run = reading.find_run_dir(args.run)
    print(artefact.export(run, path, method=str(report_runs.method_of(record.saved_config(run)))))
    return
  run_dir = reading.find_run_dir(args.run)
  trainer, state = assemble.load(args.run, backend="native")  # host physics: pictures only
  _check_scenes(trainer, args.run, "picture")
  step = int(state.step)
  default = run_dir / _derived_name(args.run, run_dir, "synergies", step)
  out = pathlib.Path(args.out) if args.out else default
  paths = synergy_pictures.write(trainer, state.params, out, k=args.k, force=args.force,
                                 title=f"{run_dir.resolve().name} step {step}:")
  for path in paths:
    print(path)


def cmd_render(args) -> None:
  from discosyn_jax import tasks
  from discosyn_jax.run import reading
  from discosyn_jax import assemble
  from discosyn_jax.viz import videos

  run_dir = reading.find_run_dir(args.run)
  trainer, state = assemble.load(args.run, backend="native")
  _check_scenes(trainer, args.run, "film")
  videos.task_index(trainer.config, args.task)  # a bad task fails before any rollout
  name = _derived_name(args.run, run_dir, tasks.label(args.task), int(state.step))
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
  from discosyn_jax.experiments import paper

  out = pathlib.Path(args.out)
  if args.name == "confirm":
    return _confirm(args, out)
  if args.plan is not None:
    raise UsageError(f"a plan file is for `discosyn experiment confirm PLAN`, not {args.name}")
  seeds = tuple(args.seeds) if args.seeds else getattr(paper.SCALES.get(args.scale), "seeds", (0,))
  only = f", methods {' '.join(args.methods)}" if args.methods else ""
  print(f"experiment {args.name} at scale {args.scale}, seeds {' '.join(map(str, seeds))}{only}, "
        f"on {args.hand}, in {out}")
  start = time.perf_counter()
  paper.run(args.name, out, args.scale, seeds, decoder_from=args.decoder_from,
            methods=args.methods, hand=args.hand, progress=args.progress)
  print(f"experiment {args.name} finished in {(time.perf_counter() - start) / 60:.1f} min")


def _confirm(args, out: pathlib.Path) -> None:
  """`discosyn experiment confirm PLAN --out DIR`: the plan's runs, exactly as it gives them."""
  from discosyn_jax.experiments import confirm

  if args.plan is None:
    raise UsageError("discosyn experiment confirm PLAN: give the plan file")
  given = [flag for flag, value in (("--seeds", args.seeds), ("--methods", args.methods),
                                    ("--decoder-from", args.decoder_from)) if value]
  if given:
    raise UsageError(f"a plan gives its rows' configs and seeds: drop {' '.join(given)}")
  print(f"confirmation plan {args.plan}, in {out}")
  start = time.perf_counter()
  confirm.run(args.plan, out, progress=args.progress)
  print(f"confirmation plan {args.plan} finished in {(time.perf_counter() - start) / 60:.1f} min; "
        f"its verdicts: discosyn report {shlex.quote(str(out))}")


def cmd_keep(args) -> None:
  from discosyn_jax.experiments import record

  for folder in record.keep(pathlib.Path(args.out), pathlib.Path(args.dest)):
    print(folder)


def cmd_upgrade(args) -> None:
  from discosyn_jax import config as config_lib
  from discosyn_jax.run import logs, owner, reading

  for run in map(pathlib.Path, args.runs):
    owner.refuse_if_written(run)
    run_dir = reading.find_run_dir(run)
    added = config_lib.upgrade(run_dir / layout.CONFIG_FILE)
    archived = run_dir / (layout.METRICS_FILE + logs.ARCHIVED)
    if archived.is_file():  # a record's metrics: to what a record keeps today
      logs.archive(archived, config_lib.load(run_dir / layout.CONFIG_FILE).unroll_length)
    print(f"{run}: {'added ' + ', '.join(added) if added else 'up to date'}")


def cmd_report(args) -> None:
  from discosyn_jax.experiments import report

  path = report.write(args.runs, pathlib.Path(args.out), threshold=args.threshold,
                      with_tsne=not args.no_tsne, force=args.force, final_k=args.final_k)
  print(path)
