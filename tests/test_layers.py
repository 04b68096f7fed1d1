"""The house in layers (docs/ARCHITECTURE.md): the library's core never imports the tasks
(discosyn_jax.tasks), the assembler (discosyn_jax.assemble), the experiments
(discosyn_jax.experiments) or the command line (discosyn); the tasks never import the
assembler, the experiments or the command line; the assembler never the experiments or
the command line; the experiments never import the command line; and no module imports
itself back through others. Every
import counts, those inside functions too. The package's own __init__ (the public API) sits
above them all."""

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("discosyn", "discosyn_jax")
TASKS, EXPERIMENTS = "discosyn_jax.tasks", "discosyn_jax.experiments"
ASSEMBLE = "discosyn_jax.assemble"  # a run from a config: the tasks' envs and a Trainer
API = ("discosyn_jax", "discosyn_jax.api")  # the package's top: the public API
# each layer may import those before it; the command line is a client of the API
LAYERS = ("discosyn_jax", TASKS, ASSEMBLE, EXPERIMENTS, API, "discosyn")


def layer(module: str) -> int:
  """The rank of `module`'s layer."""
  if module in API:
    return LAYERS.index(API)
  for rank, name in reversed(list(enumerate(LAYERS))):
    if name is API:
      continue
    if module == name or module.startswith(name + "."):
      return rank
  raise ValueError(module)


def modules() -> dict[str, pathlib.Path]:
  out = {}
  for package in PACKAGES:
    for path in sorted((ROOT / package).rglob("*.py")):
      parts = path.relative_to(ROOT).with_suffix("").parts
      out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
  return out


def imports(name: str, path: pathlib.Path, known) -> set[str]:
  """The project's modules that `name` imports (a name imported from a package counts as
  its module where it is one, else as the package)."""
  package = name if path.name == "__init__.py" else name.rpartition(".")[0]
  found = set()
  for node in ast.walk(ast.parse(path.read_text(), str(path))):
    if isinstance(node, ast.Import):
      targets = [alias.name for alias in node.names]
    elif isinstance(node, ast.ImportFrom):
      base = node.module or ""
      if node.level:  # relative
        base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1]
                        + ([node.module] if node.module else []))
      targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base
                 for alias in node.names]
    else:
      continue
    for target in targets:
      while target and target not in known:  # `import a.b.c`: the deepest module known
        target = target.rpartition(".")[0]
      if target and target != name:
        found.add(target)
  return found


def graph() -> dict[str, set[str]]:
  known = modules()
  return {name: imports(name, path, known) for name, path in known.items()}


def test_no_layer_imports_one_above_it():
  wrong = [f"{name} imports {target}" for name, targets in graph().items()
           for target in targets if layer(target) > layer(name)]
  assert not wrong, "\n".join(sorted(wrong))


def test_no_module_imports_itself_back():
  edges, cycles, state = graph(), [], {}

  def visit(node, path):
    state[node] = "open"
    for target in sorted(edges[node]):
      if state.get(target) == "open":
        cycles.append(" -> ".join(path[path.index(target):] + [target]))
      elif target not in state:
        visit(target, path + [target])
    state[node] = "done"

  for node in sorted(edges):
    if node not in state:
      visit(node, [node])
  assert not cycles, "\n".join(cycles)


def test_the_walk_sees_the_imports_it_judges():
  edges = graph()  # the walk itself: a test that finds no import could never fail
  assert "discosyn_jax.run.checkpoints" in edges["discosyn_jax.training.loop"]
  assert "discosyn_jax.training.trainer" in edges["discosyn_jax.assemble"]
  assert "discosyn_jax.assemble" in edges["discosyn_jax.experiments.record"]  # inside a function
  assert TASKS in edges["discosyn_jax.experiments.presets"]


# what builds a run's Trainer and trains it: the environment layer imports none of it
TRAINING = ("discosyn_jax.training", "discosyn_jax.agent", "discosyn_jax.experiments")


def test_the_environment_layer_knows_nothing_of_training():
  """The envs and the task registry build environments only; the one place that assembles
  envs and a Trainer from a config is discosyn_jax.assemble."""
  environment = [name for name in graph() if name.startswith(("discosyn_jax.env", "discosyn_jax.tasks"))]
  assert "discosyn_jax.tasks.registry" in environment and "discosyn_jax.env.hand_env" in environment
  wrong = [f"{name} imports {target}" for name in environment for target in graph()[name]
           if target.startswith(TRAINING)]
  assert not wrong, "\n".join(sorted(wrong))


# the library's parts (docs/ARCHITECTURE.md), each importing only parts of a lower rank; at
# the top level of discosyn_jax, the modules every part may use
PART_RANK = {"training": 3, "synergies": 2, "viz": 2, "agent": 1, "run": 1, "env": 0.25, "decoders": 0.4,
             "config": 0.5, "checks": 0, "atomic": 0, "quiet_mjx": 0}


def part(module: str) -> str | None:
  """The part of the library that holds `module` (None: the package's own __init__)."""
  parts = module.split(".")
  if layer(module) != 0:  # the tasks, the experiments, the API
    return None
  return parts[1] if parts[0] == "discosyn_jax" and len(parts) > 1 else None


def test_the_library_is_its_parts_each_importing_only_the_parts_below_it():
  library = {name: targets for name, targets in graph().items() if part(name)}
  assert set(map(part, library)) == set(PART_RANK), "a part ARCHITECTURE.md does not name"
  wrong = [f"{name} imports {target}" for name, targets in library.items() for target in targets
           if part(target) and part(target) != part(name)
           and PART_RANK[part(target)] >= PART_RANK[part(name)]]
  assert not wrong, "\n".join(sorted(wrong))
