"""Which residual schedule (agent/residual.py) on the planted test bed with targets partly
outside the span: the `planted` preset's run (planted-disco3-linear, 2.05 M env steps of
four tasks) on `planted_out<n>`, the planted tasks with `outside` > 0 (registered by this
study for its own process), once per variant and seed, one run at a time; then a table per
variant: final success, the mean over the evaluation curve and the final return (an
episode pays at most 10; each a mean over the tasks), the action shares at the end, and the
decoder's overlap with the planted span. A goal whose target lies mostly in the span can
succeed without the residual: success alone undersells what the part outside costs.

  python -m studies.residual_planted --out runs/residual-planted --seeds 0 1
"""

from __future__ import annotations

import argparse
import functools
import pathlib

VARIANTS = {  # name: the residual's fields
    "none": dict(residual=0.0),
    "const0.3": dict(residual=0.3),
    "ramp0.3": dict(residual=0.3, residual_ramp=0.5),
    "ramp0.15": dict(residual=0.15, residual_ramp=0.5),
}
PRESET = "planted-disco3-linear"


def register_outside_tasks(outside: float) -> tuple[str, ...]:
  """planted_out0-3: planted0-3 with `outside`, in this process's registry."""
  from discosyn_jax.tasks import planted, registry

  return tuple(registry.register(
      f"planted_out{n}", planted.PlantedEnv,
      functools.partial(planted.default_config, index=n, outside=outside),
      f"planted{n} with a target part outside the span ({outside})") for n in range(4))


def config_for(variant: str, seed: int, task_names, steps: int | None):
  from discosyn_jax.experiments import presets

  config = presets.preset(PRESET).replace(tasks=task_names, seed=seed, **VARIANTS[variant])
  return (config if steps is None else config.replace(steps=steps)).validate()


def summary(run_dir: pathlib.Path) -> dict:
  """Final success, its mean over the evaluation curve, the final return, the action shares
  and the overlap with the planted span at the end (each a mean over the tasks)."""
  import discosyn_jax as ds

  run = ds.read_run(run_dir)
  mean = lambda values: sum(values) / len(values) if values else None
  shares = run.action_shares().values()
  overlap = next((row["decoder/overlap_planted"] for row in reversed(run.metrics)
                  if "decoder/overlap_planted" in row), float("nan"))
  last = run.evaluations[-1]
  return {"env_steps": last.get("env_steps"), "final": mean(list(run.success.values())),
          "curve": run.mean_success,
          "return": mean([last[f"{t}/return"] for t in run.config.tasks]),
          "synergy": mean([s for s, _ in shares]), "residual": mean([r for _, r in shares]),
          "overlap": overlap}


def train_each(out: pathlib.Path, variants, seeds, outside: float, config_of,
               steps: int | None = None) -> list[tuple[str, int, pathlib.Path]]:
  """(variant, seed, its folder) of each run, trained one at a time on planted_out<n>
  (`config_of(variant, seed, task names, steps)` its config); a finished run is kept (its
  final checkpoint, or its closing evaluation where only its record is left)."""
  from discosyn_jax import assemble

  names = register_outside_tasks(outside)
  done = []
  for variant in variants:
    for seed in seeds:
      run_dir = out / f"{variant}-outside{outside}-seed{seed}"
      if not ((run_dir / "final").exists() or (run_dir / "closing.json").exists()):
        assemble.train(config_of(variant, seed, names, steps), run_dir,
                       force=run_dir.exists(), progress=False, log=lambda *a: None)
      done.append((variant, seed, run_dir))
  return done


def main(argv=None):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/residual-planted"))
  parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
  parser.add_argument("--outside", type=float, default=0.5,
                      help="the target's part outside the span (default: %(default)s)")
  parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
  parser.add_argument("--steps", type=int, help="train steps (default: the preset's)")
  args = parser.parse_args(argv)

  rows = [(variant, seed, summary(run_dir)) for variant, seed, run_dir in
          train_each(args.out, args.variants, args.seeds, args.outside, config_for, args.steps)]
  print("| variant | seed | env steps | final success | success, mean over the curve | "
        "final return | mean abs D(z) | mean abs rho r | overlap with the span |")
  print("|---|---|---|---|---|---|---|---|---|")
  share = lambda value: "–" if value is None else f"{value:.3f}"
  for variant, seed, s in rows:
    print(f"| {variant} | {seed} | {s['env_steps']:,} | {s['final']:.2f} | {s['curve']:.2f} | "
          f"{s['return']:.2f} | {share(s['synergy'])} | {share(s['residual'])} | {s['overlap']:.2f} |")


if __name__ == "__main__":
  main()
