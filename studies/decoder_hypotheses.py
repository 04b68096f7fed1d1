"""Why does the DiscoSyn decoder not learn? One variant of `set1-disco3-linear`
(as it was before z was bounded, unless a variant says) per hypothesis, trained and summarised side by side.

  python studies/decoder_hypotheses.py --variants baseline squash --seeds 0 1 --steps 100
  python studies/decoder_hypotheses.py --summary runs/hypotheses      # the table only

Each run goes to OUT/<variant>-seed<n> (an unfinished one is resumed, a finished one kept);
the summary gives, per run, env steps, the final deterministic success per valve, and the
decoder's movement from its initial state (diagnostics.py): relative change of W and the
principal-angle cosines. Results and commands: docs/notes/2026-11-29-a-decoder-does-not-learn.md.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import discosyn_jax  # noqa: E402
from discosyn_jax.run import jax_setup  # noqa: E402

jax_setup.setup_jax()  # the compile cache; MJX imported quietly

from discosyn_jax import config as config_lib  # noqa: E402
from discosyn_jax.run import layout, logs
from discosyn_jax.experiments import presets, record  # noqa: E402

# variant -> TrainConfig changes to set1-disco3-linear (one hypothesis each)
VARIANTS = {
    "baseline": dict(squash_z=False),  # the preset as it was before z was bounded
    "random": dict(squash_z=False, freeze_decoder=True),  # its control: decoder frozen at start
    "squash": dict(squash_z=True),  # z bounded: a = W tanh(z) + c (the preset now)
    "squash-random": dict(squash_z=True, freeze_decoder=True),
    "nobias": dict(squash_z=False, decoder_bias=False),  # the paper's a = z phi
    "decoder-noise": dict(squash_z=False, init_z_std=0.3, init_action_std=0.6),  # 20-D exploring
    "squash-decoder-noise": dict(squash_z=True, init_z_std=0.3, init_action_std=0.6),
    "alpha2x10": dict(squash_z=False, alpha2=0.1),
    "calm-ppo": dict(squash_z=False, update_epochs=2, learning_rate=1e-4),  # smaller PPO steps
}


def summary(out: pathlib.Path) -> str:
  lines = ["| run | env steps | valve0 | valve1 | valve2 | valve3 | mean | W change | cosines |",
           "|---|---|---|---|---|---|---|---|---|"]
  for run in sorted(p for p in out.iterdir() if (p / layout.CONFIG_FILE).is_file()):
    config = config_lib.load(run / layout.CONFIG_FILE)
    evals = logs.read_log(run / layout.EVAL_FILE)
    metrics = logs.read_log(run / layout.METRICS_FILE)
    if not evals:
      continue
    final = evals[-1]
    success = [final.get(f"{t}/success", float("nan")) for t in config.tasks]
    moved = [m for m in metrics if "decoder/change" in m]
    cos = (" / ".join(f"{moved[-1][f'decoder/cos_{k}']:.3f}" for k in range(1, config.n_synergies + 1))
           if moved else "–")
    change = f"{moved[-1]['decoder/change']:.1%}" if moved else "–"
    lines.append(f"| {run.name} | {final['env_steps']:,} | "
                 + " | ".join(f"{s:.2f}" for s in success)
                 + f" | {sum(success) / len(success):.2f} | {change} | {cos} |")
  return "\n".join(lines)


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=["baseline"],
                      help="hypotheses to train (see VARIANTS)")
  parser.add_argument("--seeds", type=int, nargs="+", default=[0], help="one run per seed")
  parser.add_argument("--steps", type=int, default=100,
                      help="train steps per run (10,240 env steps each at 128 envs per valve)")
  parser.add_argument("--eval-every", type=int, default=25, help="train steps between evaluations")
  parser.add_argument("--out", default="runs/hypotheses", help="folder of the runs")
  parser.add_argument("--summary", metavar="OUT", help="print the table of OUT and stop")
  args = parser.parse_args(argv)
  if args.summary:
    print(summary(pathlib.Path(args.summary)))
    return
  out = pathlib.Path(args.out)
  base = presets.preset("set1-disco3-linear")
  for variant in args.variants:
    for seed in args.seeds:
      config = base.replace(seed=seed, steps=args.steps, eval_every=args.eval_every,
                            checkpoint_every=args.eval_every, **VARIANTS[variant]).validate()
      run = out / f"{variant}-seed{seed}"
      if not record.finished(run, config):
        discosyn_jax.train(config, run, resume=(run / layout.CONFIG_FILE).is_file(), progress=False)
  print(summary(out))


if __name__ == "__main__":
  main()
