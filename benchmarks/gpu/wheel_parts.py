"""The wheels of .whl/ in folders small enough to travel one per call to a GPU machine, and
joined again there: what a call carries beside the tracked tree is bounded (the tree is
~35 MB, a call 64 MiB in all), and warp-lang's wheel alone is 149 MB.

  python benchmarks/gpu/wheel_parts.py split [--mb 25]   # .whl/*.whl -> .whl-parts/1, 2, ...
  python benchmarks/gpu/wheel_parts.py join              # .whl-parts/* -> .whl/ (checked)

`split` packs whole wheels into parts first-fit and cuts a wheel larger than a part into
pieces; each part holds a manifest of every wheel's size and SHA-256. `join` rebuilds
.whl/ from whichever parts have arrived and stops with one line naming the pieces still
missing, so a partial transfer never installs a truncated wheel.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import pathlib
import shutil
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
MANIFEST = "manifest.json"


def _sha256(path: pathlib.Path) -> str:
  digest = hashlib.sha256()
  with open(path, "rb") as f:
    for block in iter(lambda: f.read(1 << 20), b""):
      digest.update(block)
  return digest.hexdigest()


def split(wheels: pathlib.Path, parts: pathlib.Path, part_bytes: int) -> list[pathlib.Path]:
  """The wheels of `wheels` as folders parts/1, 2, ... of at most `part_bytes` each."""
  files = sorted(wheels.glob("*.whl"), key=lambda p: -p.stat().st_size)
  if not files:
    raise ValueError(f"{wheels} holds no wheel: run benchmarks/gpu/wheels.sh first")
  manifest = {p.name: {"bytes": p.stat().st_size, "sha256": _sha256(p),
                       "pieces": -(-p.stat().st_size // part_bytes)} for p in files}
  pieces = []  # (size, source, offset, name in its part)
  for p in files:
    n = manifest[p.name]["pieces"]
    for i in range(n):
      size = min(part_bytes, p.stat().st_size - i * part_bytes)
      pieces.append((size, p, i * part_bytes, p.name if n == 1 else f"{p.name}.piece{i:02d}"))
  bins: list[list] = []  # first fit, largest first
  for piece in pieces:
    home = next((b for b in bins if sum(x[0] for x in b) + piece[0] <= part_bytes), None)
    if home is None:
      bins.append(home := [])
    home.append(piece)
  shutil.rmtree(parts, ignore_errors=True)
  folders = []
  for k, contents in enumerate(bins, 1):
    folder = parts / str(k)
    folder.mkdir(parents=True)
    for size, source, offset, name in contents:
      with open(source, "rb") as f:
        f.seek(offset)
        (folder / name).write_bytes(f.read(size))
    (folder / MANIFEST).write_text(json.dumps(manifest, indent=1))
    folders.append(folder)
  return folders


def join(parts: pathlib.Path, wheels: pathlib.Path) -> list[pathlib.Path]:
  """.whl/ rebuilt from every part that has arrived; ValueError naming what is missing."""
  folders = sorted((p for p in parts.glob("*") if (p / MANIFEST).is_file()), key=lambda p: p.name)
  if not folders:
    raise ValueError(f"{parts} holds no part: carry .whl-parts/<k> with each call")
  manifest = json.loads((folders[0] / MANIFEST).read_text())
  found = {f.name: f for folder in folders for f in folder.iterdir() if f.name != MANIFEST}
  missing = [f"{name}.piece{i:02d}" if meta["pieces"] > 1 else name
             for name, meta in manifest.items() for i in range(meta["pieces"])
             if (f"{name}.piece{i:02d}" if meta["pieces"] > 1 else name) not in found]
  if missing:
    raise ValueError(f"{len(missing)} of the wheels' pieces have not arrived: {', '.join(missing)}")
  wheels.mkdir(parents=True, exist_ok=True)
  out = []
  for name, meta in manifest.items():
    target = wheels / name
    names = [f"{name}.piece{i:02d}" for i in range(meta["pieces"])] if meta["pieces"] > 1 else [name]
    with open(target, "wb") as f:
      for piece in names:
        f.write(found[piece].read_bytes())
    if target.stat().st_size != meta["bytes"] or _sha256(target) != meta["sha256"]:
      target.unlink()
      raise ValueError(f"{name} joined from its pieces does not match its manifest")
    out.append(target)
  return out


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  parser.add_argument("command", choices=["split", "join"])
  parser.add_argument("--mb", type=float, default=25.0, help="MB a part holds at most (split)")
  parser.add_argument("--wheels", type=pathlib.Path, default=ROOT / ".whl")
  parser.add_argument("--parts", type=pathlib.Path, default=ROOT / ".whl-parts")
  args = parser.parse_args(argv)
  try:
    if args.command == "split":
      for folder in split(args.wheels, args.parts, int(args.mb * 1e6)):
        print(f"{folder}: {sum(f.stat().st_size for f in folder.iterdir()) / 1e6:.1f} MB")
    else:
      print(f"{len(join(args.parts, args.wheels))} wheels in {args.wheels}")
  except ValueError as err:
    print(f"wheel_parts: {err}", file=sys.stderr)
    return 2
  return 0


if __name__ == "__main__":
  sys.exit(main())
