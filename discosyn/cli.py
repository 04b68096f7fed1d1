"""The `discosyn` command: train, eval, synergies, render, experiment, keep, report, bench,
demo, tasks, render-scenes, upgrade; its flags, and how it ends (one line and exit 2 for bad input,
checks.BadInput; a bug's traceback and a line that says it is one, exit 1; 128 + the signal for
Ctrl-C / SIGTERM). The commands themselves are in commands.py."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import traceback

from discosyn import commands


class _Parser(argparse.ArgumentParser):
  """Bad input is one line (which flag, what is wrong), exit status 2: argparse's own also
  printed the command's whole usage; `--help` shows it."""

  def error(self, message: str):
    self.exit(2, f"{self.prog}: error: {message}\n")


def _yes_no(text: str) -> bool:
  """A true/false flag's value: yes or no (bool("no") would be True)."""
  if text not in ("yes", "no"):
    raise argparse.ArgumentTypeError(f"yes or no, not {text!r}")
  return text == "yes"


def _shipped_synergies() -> list[str]:
  """The names of the synergy files that ship (synergies/shipped/), found without JAX."""
  import pathlib

  import discosyn_jax

  return sorted(p.stem for p in (pathlib.Path(discosyn_jax.__file__).parent / "synergies"
                                 / "shipped").glob("*.npz"))


def build_parser() -> argparse.ArgumentParser:
  from discosyn_jax import config as config_lib, decoders
  from discosyn_jax.env import settings
  from discosyn_jax.experiments import presets  # TrainConfig only, no JAX

  parser = _Parser(prog="discosyn", description=__doc__)
  sub = parser.add_subparsers(dest="command", required=True)
  quick = presets.PRESETS["quickstart"]

  def preset_default(field: str) -> str:
    value = getattr(quick, field)
    value = (" ".join(value) if isinstance(value, tuple) else
             ("yes" if value else "no") if isinstance(value, bool) else value)
    return f"default: the preset's; quickstart's is {value}"

  docs = config_lib.field_docs()  # each field's help, written once beside the field
  choices = {"decoder": tuple(decoders.KINDS), "decoder_init": config_lib.DECODER_INITS,
             "discriminator_target": config_lib.DISCRIMINATOR_TARGETS,
             "backend": settings.BACKENDS,
             "physics": settings.PHYSICS}

  p = sub.add_parser("train", help="train synergies and policies (a preset, flags replace fields)")
  p.add_argument("--preset", help="a named config of discosyn_jax/experiments/presets.py: "
                 f"{', '.join(presets.PRESETS)} (default: quickstart; with --resume: the run's "
                 "own)")
  p.add_argument("--tasks", nargs="+", help=f"{docs['tasks']}; or FILE.py:CLASS, a task of "
                 "one's own (docs/YOUR_TASK.md); " + preset_default("tasks"))
  p.add_argument("--hand", help=f"{docs['hand']}; {preset_default('hand')}")
  for flag, field in commands.TRAIN_FLAGS.items():  # the rest of the fields' flags
    kind = type(getattr(quick, field))
    p.add_argument(f"--{flag.replace('_', '-')}",
                   type={str: None, bool: _yes_no}.get(kind, kind), choices=choices.get(field),
                   metavar="{yes,no}" if kind is bool else None,
                   help=f"{docs[field]}; {preset_default(field)}")
  p.add_argument("--decoder-from", help="learn in the frozen synergy space of a run folder, a "
                 "synergy file (.npz) or a shipped synergy file's name "
                 f"({', '.join(_shipped_synergies())}): its decoder, no discriminator bonus or "
                 "decoder entropy (default: none, the decoder is learned)")
  p.add_argument("--stop-at", type=float, help="end the run at the first evaluation at which "
                 "every task's deterministic success is at least this, 0-1 (default: run all "
                 "--steps)")
  p.add_argument("--out", help="run directory (default: runs/<preset>-seed<seed>)")
  p.add_argument("--resume", action="store_true", help="continue the run in --out")
  p.add_argument("--force", action="store_true", help="replace the run in --out")
  p.add_argument("--no-progress", action="store_true", help="no progress bar (it is a line every "
                 "tenth of the run when stderr is not a terminal)")
  add_device_flags(p)
  p.set_defaults(fn=commands.cmd_train)

  p = sub.add_parser("eval", help="evaluate a run (its latest checkpoint) or one checkpoint")
  p.add_argument("run", help="a run directory or a checkpoint folder in one")
  p.add_argument("--episodes", type=int, help="episodes per task (default: the run's eval_envs)")
  p.add_argument("--backend", choices=settings.BACKENDS,
                 help="physics backend (default: the run's)")
  p.set_defaults(fn=commands.cmd_eval)

  p = sub.add_parser("synergies", help="pictures of a run's synergies: the hand along each "
                     "synergy, and the matrix of a linear decoder (needs EGL or OSMesa)")
  p.add_argument("run", help="a run directory or a checkpoint folder in one")
  p.add_argument("--out", help="folder for postures.png and matrix.png (default: RUN/synergies)")
  p.add_argument("--k", type=float, default=1.0, help="the hand is shown at z = -k, 0, +k "
                 "(in units of z, whose prior is a unit normal; default: %(default)s)")
  p.add_argument("--export", metavar="FILE", help="write the run's synergies as a synergy file "
                 "(.npz) that says what it is: its hand and actuators, what it was learned on and "
                 "how well (docs/TAKE_HOME.md); no pictures (default: none, the pictures)")
  p.add_argument("--force", action="store_true", help="replace pictures (or the --export file) "
                 "already there")
  p.set_defaults(fn=commands.cmd_synergies)

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
  p.set_defaults(fn=commands.cmd_render)

  p = sub.add_parser(
      "experiment", help="run one of the paper's experiments, or all, at a scale "
      "(discosyn_jax/experiments/paper.py); finished steps are kept, unfinished ones resumed",
      description="Run one of the paper's experiments at a scale, a folder per step in --out. "
      "A step whose folder holds a finished run of the same config is kept: its final "
      "checkpoint, or its record alone (config.json, eval.jsonl, experiment.json, "
      "metrics.jsonl.xz, decoder.npz, z.npz: what `discosyn keep` copies), so that a folder "
      "of records (docs/results/...) is continued, not retrained; an unfinished step is "
      "resumed. Every run ends by writing its record, and a later step reads the records of "
      "those before it (a matched or transferred decoder its decoder.npz, a fitted space its "
      "synergy file; only a fit rolls out its PPO run's checkpoint, and a PPO run kept as a "
      "record alone is trained again for it); `discosyn report` needs no checkpoint.")
  p.add_argument("name", help="all: the rows of the paper's tables with today's defaults "
                 "(paper.PAPER_ROWS: set #1's DiscoSyn, its controls and the baselines, then "
                 "the sparse valve and transfer from each seed's default decoder, set #2 last); "
                 "table1 | table2: one table's rows, the same steps as all's (a part of it); "
                 "discosyn-set1 | discosyn-set2 (every start and control tried) | "
                 "baselines-set1 | baselines-set2 | transfer | sparse (from the default "
                 "row's decoder, then from the residual row's, acting with its residual); "
                 "the planted-synergy "
                 "test bed: discosyn-planted | discosyn-planted_slack; confirm PLAN: the runs of "
                 "a confirmation plan file, exactly as it gives them "
                 "(discosyn_jax/experiments/confirm.py)")
  p.add_argument("plan", nargs="?", help="confirm: the plan file (JSON: rows with their full "
                 "configs and seeds, hypotheses, the decision); its runs are folders "
                 "<row>-seed<n> in --out, and `discosyn report` prints its verdicts (default: none; "
                 "the other experiments take none)")
  p.add_argument("--scale", default="cpu", help="ci (seconds per run) | cpu (minutes per run on "
                 "2 cores) | long (cpu's runs 8x as long: the budget a row needs) | gpu (one "
                 "accelerator); default: %(default)s")
  p.add_argument("--seeds", type=int, nargs="+",
                 help="training seeds: every step runs once per seed (default: the scale's, "
                 "0 1 2 for cpu and gpu, 0 for ci)")
  p.add_argument("--out", default="runs/experiments",
                 help="folder of the experiment's runs (default: %(default)s)")
  p.add_argument("--decoder-from", help="transfer / sparse: the frozen decoder of this run folder, "
                 f"synergy file or shipped name ({', '.join(_shipped_synergies())}), instead of "
                 "training their own DiscoSyn run first (default: none)")
  p.add_argument("--methods", nargs="+", metavar="METHOD",
                 help="only these methods' runs and the runs they need, e.g. DiscoSyn3-L "
                 "Random3-L, or PCA4 (with its PPO run and fit); default: every method")
  add_hand_flag(p, "every run on this hand; folders end in <hand>-seed<n> on another than ours")
  p.add_argument("--progress", action="store_true", help="a progress bar per run")
  p.set_defaults(fn=commands.cmd_experiment)

  p = sub.add_parser("keep", help="copy the record of every finished run, fit and matched "
                     "decoder of an experiment's folder into another (to commit it)",
                     description="Copy into DEST/<folder> the record of every step folder of "
                     "OUT: a finished run's config.json, eval.jsonl, experiment.json, "
                     "metrics.jsonl.xz and, where it has them, decoder.npz and z.npz; a fit's "
                     "explained_variance.json and synergy files; a matched control's "
                     "decoder.npz. Checkpoints, TensorBoard files, plots and metrics.jsonl are "
                     "left out: `discosyn experiment` continues and `discosyn report` reports "
                     "from the records alone. A run without a record (unfinished) is named "
                     "and left out.")
  p.add_argument("out", help="an experiment's folder (the --out of `discosyn experiment`)")
  p.add_argument("dest", help="the folder to copy the records into (e.g. docs/results/NAME)")
  p.set_defaults(fn=commands.cmd_keep)

  p = sub.add_parser("report", help="REPORT.md and figures from run folders: solved tasks, "
                     "interval estimates (IQM, mean, P(improvement), performance profiles), "
                     "explained variance, curves, t-SNE, transfer, sparse reward",
                     description="REPORT.md and figures from run folders or their records "
                     "alone (`discosyn keep`): per set, the IQM and mean of the final "
                     "success and of the mean over the curve with 95 % stratified bootstrap "
                     "intervals (rliable, a fixed seed), the probability that the default row "
                     "improves on each other row, and a performance profile; each task's final success, mean "
                     "(min–max) [seeds] with the paper's marks, and each row's success over "
                     "the tasks at the end and over the curve; explained variance; curves; "
                     "the synergy subspaces; t-SNE of z (z.npz, else the checkpoint); "
                     "transfer and the sparse valve by final success, mean over the curve, "
                     "env steps to the threshold (and to the first reward on the sparse "
                     "valve). The text names the folders relative to the report's own and "
                     "holds no date: the same folders give the same REPORT.md anywhere.")
  p.add_argument("runs", nargs="+", help="run folders, synergy-fit folders, or folders of them")
  p.add_argument("--out", default="report",
                 help="folder for REPORT.md and its figures (default: %(default)s)")
  p.add_argument("--threshold", type=float, default=0.8,
                 help="final success rate (a fraction, 0-1) at or above which a task counts as "
                 "solved (default: %(default)s)")
  p.add_argument("--final-k", type=int, default=3, metavar="K",
                 help="a run's final success is the mean of its last K evaluations, so that one "
                 "evaluation cannot swing it (default: %(default)s; a confirmation plan's "
                 "hypotheses use the plan's own)")
  p.add_argument("--no-tsne", action="store_true", help="skip the t-SNE (it rolls policies out)")
  p.add_argument("--force", action="store_true", help="replace a report already in --out")
  p.set_defaults(fn=commands.cmd_report)

  p = sub.add_parser("upgrade", help="write into the config.json of runs made by an older "
                     "release the fields added since, with the values it ran, and thin a "
                     "record's metrics to what a record keeps")
  p.add_argument("runs", nargs="+", help="run directories")
  p.set_defaults(fn=commands.cmd_upgrade)

  p = sub.add_parser("demo", help="build task scenes, step them with random actions, print figures")
  p.add_argument("tasks", nargs="*", default=["set1"], help="tasks or task sets (default: set1)")
  p.add_argument("--backend", default="auto", choices=settings.BACKENDS,
                 help="physics backend (default: %(default)s: native on a CPU, mjx on an "
                 "accelerator)")
  p.add_argument("--batch", type=int, default=16, help="parallel envs per task (default: "
                 "%(default)s)")
  p.add_argument("--seed", type=int, default=0, help="seed of the initial states and actions "
                 "(default: %(default)s)")
  add_hand_flag(p)
  p.set_defaults(fn=commands.cmd_demo)

  p = sub.add_parser("tasks", help="list the tasks with observation size and set membership")
  p.set_defaults(fn=commands.cmd_tasks)

  p = sub.add_parser("render-scenes", help="write a PNG of each task scene (needs EGL or OSMesa)")
  p.add_argument("tasks", nargs="*", default=["set1"], help="tasks or task sets (default: set1)")
  p.add_argument("--out", default="docs/scenes", help="folder for TASK.png (default: %(default)s)")
  p.add_argument("--step", type=int, default=14, help="control steps of the task's scripted motion "
                 "before the picture (default: %(default)s)")
  p.add_argument("--seed", type=int, default=0, help="draws the initial state (default: %(default)s)")
  add_hand_flag(p)
  p.set_defaults(fn=commands.cmd_render_scenes)
  add_bench_parser(sub)
  return parser


def add_hand_flag(p, what: str = "the hand") -> None:
  from discosyn_jax.config import TrainConfig

  p.add_argument("--hand", default=TrainConfig.hand,
                 help=f"{what}: shadow20 | leap16 | path/to/hand.xml[:PALM_SITE] "
                 "(docs/YOUR_HAND.md; default: %(default)s)")


def add_device_flags(p) -> None:
  p.add_argument("--devices", type=int, help="devices to split the env batch over (default: all "
                 "of them)")
  p.add_argument("--distributed", action="store_true",
                 help="multi-host: jax.distributed.initialize() first (docs/SCALING.md)")


def add_bench_parser(sub) -> None:
  from discosyn_jax.experiments import bench

  p = sub.add_parser("bench", help="physics and training env steps/s beside raw MuJoCo C")
  bench.build_parser(p)
  p.set_defaults(fn=bench.run)


def main(argv: list[str] | None = None) -> int:
  from discosyn_jax.run import stop  # light: no JAX

  args = build_parser().parse_args(argv)
  with stop.handled():  # Ctrl-C and SIGTERM, wherever they land: one line
    try:
      code = _run(args)
      stop.check()  # a stop that Python dropped where it landed (a finalizer) ends it too
      return code
    except BaseException as err:
      stopped = stop.taken(err)
      if stopped is None:
        raise
      how, signum = ("SIGTERM", signal.SIGTERM) if isinstance(stopped, stop.Terminated) else \
          ("Ctrl-C", signal.SIGINT)
      stop.quiet()
      print(f"discosyn: stopped by {how}{': ' + str(stopped) if str(stopped) else ''}",
            file=sys.stderr)
      return 128 + signum


def exit_with(code: int) -> None:
  """End the process with `code`. A command stopped by Ctrl-C or SIGTERM has already closed
  its files and said where it stopped; it ends at once, without the interpreter's shutdown,
  where orbax's idle writer threads printed "Event loop is closed" tracebacks after that line."""
  if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
    from discosyn_jax.run import stop

    stop.quiet()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
  sys.exit(code)


def entry() -> None:
  """The `discosyn` command."""
  exit_with(main())


def _run(args) -> int:
  import discosyn_jax
  from discosyn_jax.run import jax_setup, stop

  try:
    if getattr(args, "distributed", False):  # before anything touches a device
      from discosyn_jax.training import devices

      devices.initialize_distributed()
    jax_setup.setup_jax()  # before anything imports MJX (brax, through loop)
    from discosyn_jax import checks

    checks.jax_environment(discosyn_jax.XLA_FLAG)
    from discosyn_jax.env.physics import mjx_backend

    mjx_backend.check_environment()  # a misspelt DISCOSYN_MJX_IMPL, whatever the backend
    if getattr(args, "batch", 1) < 1:
      raise commands.UsageError(f"--batch must be at least 1, not {args.batch}")
    if getattr(args, "seed", None) is not None:
      checks.seed(args.seed, "--seed")
    args.fn(args)
  except Exception as err:
    if stop.under_way():  # the stop's own consequence: main says how the command stopped
      raise
    return _refused(err)
  return 0


# set to 1: a command that fails in one line prints the whole traceback before it
TRACEBACK = "DISCOSYN_TRACEBACK"


def _refused(err: Exception) -> int:
  """The one line and exit status of a command that could not do its work; for a bug, its
  traceback and a line that says so."""
  line, code = _one_line(err)
  if line is None:  # not bad input nor a failure we know: a bug in discosyn
    traceback.print_exception(err)
    print("discosyn: this is a bug in discosyn, not in what it was given: please report it "
          "with the command and the traceback above", file=sys.stderr)
    return 1
  if os.environ.get(TRACEBACK) == "1":
    traceback.print_exception(err)
  elif _is_task_error(err):  # the task's own code raised: how to see the rest
    line += f" ({TRACEBACK}=1 shows the whole traceback)"
  print(line, file=sys.stderr)
  return code


def _one_line(err: Exception) -> tuple[str | None, int]:
  from discosyn_jax.checks import BadInput
  from discosyn_jax.training.loop import TaskNotFinite, TrainingDiverged, WriteFailed

  # WriteFailed: the run's disk or folder, not its input, yet one line as an OSError
  if isinstance(err, (BadInput, TaskNotFinite, WriteFailed)):
    return f"discosyn: error: {err}", 2
  if isinstance(err, OSError):  # a file that cannot be read or written: a path, a full disk
    return (f"discosyn: error: {err.filename + ': ' if err.filename else ''}"
            f"{err.strerror or err}"), 2
  if isinstance(err, TrainingDiverged):  # the run stopped; its checkpoints are kept
    return f"discosyn: {err}", 1
  return None, 1


def _is_task_error(err: Exception) -> bool:
  task = sys.modules.get("discosyn_jax.env.task")  # not loaded: no task's code ran
  return task is not None and isinstance(err, task.TaskError)
