"""Whether two folders of runs logged the same numbers: every metrics.jsonl and eval.jsonl
under BEFORE against the file of the same path under AFTER, row by row and value by value,
the wall-clock fields aside (`wall_s`, `env_steps_per_s`: the only figures a rerun of a
seeded command may change). The proof that a restructuring changed no behaviour:

  python -m studies.same_logs BEFORE AFTER     # exit 0: every file the same
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

CLOCK = frozenset({"wall_s", "env_steps_per_s"})


def rows(path: pathlib.Path) -> list[dict]:
  return [{k: v for k, v in json.loads(line).items() if k not in CLOCK}
          for line in path.read_text().splitlines() if line.strip()]


def compare(before: pathlib.Path, after: pathlib.Path) -> list[str]:
  """One line per difference (a missing file, a row count, the first differing value)."""
  problems, files = [], sorted(p for name in ("metrics.jsonl", "eval.jsonl")
                               for p in before.rglob(name))
  if not files:
    return [f"{before} holds no logs"]
  for path in files:
    other = after / path.relative_to(before)
    if not other.is_file():
      problems.append(f"{other}: missing")
      continue
    a, b = rows(path), rows(other)
    if len(a) != len(b):
      problems.append(f"{other}: {len(b)} rows, {len(a)} before")
    for n, (x, y) in enumerate(zip(a, b)):
      if x != y:
        key = next((k for k in sorted(set(x) | set(y)) if x.get(k) != y.get(k)))
        problems.append(f"{other} row {n}: {key} = {y.get(key)!r}, {x.get(key)!r} before")
        break
  return problems


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("before", type=pathlib.Path)
  parser.add_argument("after", type=pathlib.Path)
  args = parser.parse_args(argv)
  problems = compare(args.before, args.after)
  files = len([p for n in ("metrics.jsonl", "eval.jsonl") for p in args.before.rglob(n)])
  print("\n".join(problems) or f"{files} logs, every value the same (clock fields aside)")
  return 1 if problems else 0


if __name__ == "__main__":
  sys.exit(main())
