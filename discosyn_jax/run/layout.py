"""The run folder's layout: every name in it, spelled once.

  RUN/config.json        the TrainConfig (config.py)
  RUN/metrics.jsonl      one row per train step; eval.jsonl one per evaluation (logs.py)
  RUN/tb/                the same as TensorBoard scalars
  RUN/checkpoints/<step> periodic checkpoints; RUN/final/ the last (checkpoints.py)
  RUN/plots/             the training curves (plots.py)
  RUN/writer.lock        held by the one process that writes the run (owner.py)
  RUN/replaced/          a run --force replaces, until the new one's first checkpoint
  RUN/experiment.json    what `discosyn experiment` ran it as (discosyn_jax/experiments/paper.py)
  RUN/closing.json       the closing evaluation that ends the run (closing_episodes a task)
  RUN/decoder.npz        its decoder at the end, a synergy file; RUN/z.npz the z its policy
                         picks per task; RUN/metrics.jsonl.xz: with config.json, eval.jsonl
                         and experiment.json, a finished run's record, kept without its
                         checkpoints (discosyn_jax/experiments/record.py)
"""

CONFIG_FILE = "config.json"
METRICS_FILE = "metrics.jsonl"
EVAL_FILE = "eval.jsonl"
TENSORBOARD_DIR = "tb"
PERIODIC = "checkpoints"
FINAL = "final"
PLOTS_DIR = "plots"
LOCK = "writer.lock"
ASIDE = "replaced"
EXPERIMENT_FILE = "experiment.json"
DECODER_FILE = "decoder.npz"
Z_FILE = "z.npz"
CLOSING_FILE = "closing.json"

# what a run of this product holds besides its config: --force replaces a folder only if it
# holds config.json and one of these (a config.json alone may be anyone's)
RUN_NAMES = frozenset({METRICS_FILE, EVAL_FILE, TENSORBOARD_DIR, PERIODIC, FINAL, PLOTS_DIR,
                       LOCK, ASIDE})
