"""Decoder kinds as values (discosyn_jax/decoders.py): outside the registry no module compares
a kind's name, and a kind added in one module (this one) trains a step through the command
line's path and is named, read and recorded as a kind of its own."""

import ast
import json
import pathlib

import numpy as np
import pytest

from discosyn import cli
from discosyn_jax import config as config_lib, decoders
from discosyn_jax.experiments import presets
from discosyn_jax.experiments.method import Method
from discosyn_jax.run import checkpoints, layout

ROOT = pathlib.Path(__file__).resolve().parents[1]
TINY = ["--num-envs", "4", "--unroll-length", "4", "--minibatches", "2", "--epochs", "1",
        "--steps", "1", "--eval-envs", "2", "--eval-every", "0", "--checkpoint-every", "0",
        "--no-progress"]
WIDTH = 8  # the toy's one hidden layer


def compared_kind_names(path: pathlib.Path) -> list[str]:
  """`file:line` of each comparison with a kind's name as a string ('== "linear"', 'in
  ("mlp", ...)')."""
  names = set(decoders.KINDS)

  def is_name(node) -> bool:
    if isinstance(node, ast.Constant):
      return node.value in names
    return isinstance(node, (ast.Tuple, ast.List, ast.Set)) and any(map(is_name, node.elts))

  return [f"{path.relative_to(ROOT)}:{node.lineno}"
          for node in ast.walk(ast.parse(path.read_text(), str(path)))
          if isinstance(node, ast.Compare) and any(map(is_name, [node.left, *node.comparators]))]


def test_no_module_but_the_registry_compares_a_kind_by_its_name():
  files = [p for folder in ("discosyn_jax", "discosyn", "studies", "benchmarks")
           for p in sorted((ROOT / folder).rglob("*.py")) if p != ROOT / "discosyn_jax/decoders.py"]
  assert len(files) > 50
  found = [hit for path in files for hit in compared_kind_names(path)]
  assert not found, "\n".join(found)
  planted = ROOT / "tests/fixtures/compares_a_kind.py"  # the search finds what it forbids
  assert compared_kind_names(planted) == ["tests/fixtures/compares_a_kind.py:5",
                                          "tests/fixtures/compares_a_kind.py:7"]


@pytest.fixture
def toy_kind():
  """A decoder kind of one hidden layer, letter T, registered for one test."""
  kind = decoders.register(decoders.DecoderKind(
      "toy", "T", fields=("decoder_hidden",),
      build=lambda net, blocks: blocks.GaussianHead((WIDTH,), net.action_size,
                                                    net.init_action_std, out_scale=1.0)))
  yield kind
  decoders.unregister(kind.name)


def test_a_kind_added_in_one_module_trains_through_the_command_line(tmp_path, toy_kind):
  run = tmp_path / "run"
  assert cli.main(["train", "--tasks", "planted0", "planted1", "--decoder", "toy",
                   "--synergies", "3", *TINY, "--out", str(run)]) == 0
  config = config_lib.load(run / layout.CONFIG_FILE)
  assert (config.decoder, config.decoder_init) == ("toy", "random")  # no prior starts it
  assert Method.of(config).name == "DiscoSyn3-T" and Method.parse("DiscoSyn3-T").decoder == "T"
  decoder = checkpoints.read_arrays(run / layout.FINAL, "params.params.synergy_decoder.")
  assert decoder["MLP_0.Dense_0.kernel"].shape == (3, WIDTH)  # z -> its hidden layer
  assert np.all(np.isfinite(decoder["MLP_0.Dense_0.kernel"]))
  assert json.loads((run / layout.CONFIG_FILE).read_text())["decoder"] == "toy"


def test_a_kind_is_refused_twice_and_a_name_no_kind_has_in_one_line(toy_kind):
  with pytest.raises(ValueError, match="registered already"):
    decoders.register(toy_kind)
  with pytest.raises(ValueError, match="letter 'L' names a decoder kind already"):
    decoders.register(decoders.DecoderKind("other", "L", build=toy_kind.build))
  with pytest.raises(ValueError, match="unknown decoder 'bogus'; known: linear, mlp, identity, toy"):
    presets.preset("quickstart").replace(decoder="bogus").validate()


def test_the_default_start_follows_the_decoder_a_replace_gives():
  quick = presets.preset("quickstart")
  assert quick.decoder_init == "reward"  # a linear decoder learned from scratch
  assert quick.replace(decoder="mlp").validate().decoder_init == "random"
  assert quick.replace(freeze_decoder=True).validate().decoder_init == "random"
  assert quick.replace(decoder="mlp").replace(decoder="linear").decoder_init == "reward"
  named = presets.preset("set1-disco3-linear-reward")  # a start the preset names stays
  assert named.replace(freeze_decoder=True).decoder_init == "reward"
  with pytest.raises(ValueError, match="the reward prior starts a linear decoder"):
    named.replace(decoder="mlp").validate()
  assert quick.replace(steps=7) == quick.replace(steps=7).replace()  # equal where they run the same
