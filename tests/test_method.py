"""A method as a value: every name the committed records carry reads back to itself, a name
out of order is refused, a config names its method, and the report orders rows by rank."""

import json
import pathlib

import pytest

from discosyn_jax.experiments import presets, report, report_runs
from discosyn_jax.experiments.method import Method, Residual

ROOT = pathlib.Path(__file__).resolve().parent.parent


def committed_names() -> set[str]:
  names = {json.loads(p.read_text())["method"] for p in (ROOT / "docs" / "results").rglob("experiment.json")}
  return names - {"fit"}


def test_every_committed_record_name_reads_back_to_itself():
  names = committed_names()
  assert len(names) > 30 and "DiscoSyn3-L-reward-res0.3r150 frozen-res1r150" in names
  for name in names:
    assert Method.parse(name).name == name


def test_every_committed_config_loads_under_this_release():
  """A field added since a record was written is written into it (`discosyn upgrade`) in the
  same change: a committed record that only loads after an upgrade is a report that fails."""
  from discosyn_jax import config as config_lib
  paths = [p for folder in ("docs/results", "tests/fixtures") for p in (ROOT / folder).rglob("config.json")]
  assert len(paths) > 300
  for path in paths:
    config_lib.load(path)


def test_a_name_reads_as_its_parts():
  m = Method.parse("DiscoSyn3-L-reward-res0.3r150 frozen-res1r150")
  assert (m.family, m.synergies, m.decoder, m.start, m.reuse) == ("DiscoSyn", 3, "L", "reward", "frozen")
  assert m.residual == Residual(0.3, 150) and m.acting_residual == Residual(1.0, 150)
  m = Method.parse("Random3-L-matched-wd8a200")
  assert (m.family, m.control, m.decay, m.decay_steps) == ("Random", "matched", 8.0, 200)
  assert Method.parse("DiscoSyn3-L-alpha3=0.1").tag == ("alpha3=0.1",)
  assert Method.parse("PCA4") == Method("PCA", 4) and Method.parse("PPO") == Method("PPO")


@pytest.mark.parametrize("name", ["DiscoSyn3-L-zfree-reward", "DiscoSyn3-L-res0.3-reward",
                                  "Foo3-L", "DiscoSyn3-L frozen-wd3", ""])
def test_a_name_out_of_order_or_unknown_is_refused(name):
  with pytest.raises(ValueError, match="method"):
    Method.parse(name)


def test_a_config_names_its_method():
  set1 = presets.preset("set1-disco3-linear-reward")
  assert Method.of(set1) == Method("DiscoSyn", 3, "L", start="reward")
  assert Method.of(set1.replace(freeze_decoder=True)).name == "Prior3-L-reward"
  assert Method.of(set1.replace(freeze_decoder=True, decoder_init="random")).name == "Random3-L"
  late = presets.preset("set2-disco6-linear-residual-late").replace(steps=1200)
  assert Method.of(late).name == "DiscoSyn6-L-reward-res0.3r200s400"
  assert Method.of(presets.preset("set1-ppo")).name == "PPO"
  # a frozen space without a synergy file to read: named by its config, frozen
  frozen = set1.replace(decoder_from="/nowhere/decoder.npz", freeze_decoder=True, residual=0.3,
                        residual_ramp=0.5, steps=300)
  assert report_runs.method_of(frozen).name == "DiscoSyn3-L-reward frozen-res0.3r150"


def test_a_space_learned_on_elsewhere_is_tuned_with_its_own_switches_not_frozen():
  source = ROOT / "docs/results/paper/discosyn3-l-reward-set1-seed0/decoder.npz"
  unseen = presets.preset("set1-disco3-linear-reward").replace(
      tasks=("valve_cylinder", "valve_cw"), decoder_from=str(source), decoder_init="random")
  tuned = report_runs.method_of(unseen.replace(task_noise=True, bonus_cap=True))
  # a decoder file says its architecture, not its start: the source is DiscoSyn3-L
  assert tuned.name == "DiscoSyn3-L-tasknoise-bonuscap tuned"
  assert Method.parse(tuned.name) == tuned and tuned.plain == Method("DiscoSyn", 3, "L")
  frozen = unseen.replace(freeze_decoder=True, alpha2=0.0, alpha3=0.0)
  assert report_runs.method_of(frozen).name == "DiscoSyn3-L frozen"
  with pytest.raises(ValueError, match="reuse"):
    Method("DiscoSyn", 3, "L", reuse="thawed")


def test_the_report_orders_rows_by_rank():
  names = ["Random3-L-zfree", "DiscoSyn3-L-reward-res0.3r150", "AE4", "DiscoSyn3-L",
           "Prior3-L-reward", "PPO", "DiscoSyn4-L-reward", "DiscoSyn3-L-reward", "PCA4",
           "Random3-L-matched-reward", "DiscoSyn3-L-wd8a200", "Random3-L", "DiscoSyn3-NL",
           "Random3-NL-zfree", "AE6", "Random3-L-matched-wd8a200", "DiscoSyn3-L-objects"]
  ordered = [m.name for m in report_runs.order(map(Method.parse, names))]
  assert ordered == ["PPO", "PCA4", "AE4", "AE6", "DiscoSyn3-L-reward", "Prior3-L-reward",
                     "Random3-L-matched-reward", "DiscoSyn3-L-objects", "DiscoSyn3-L",
                     "DiscoSyn3-L-wd8a200", "Random3-L-matched-wd8a200", "Random3-L",
                     "Random3-L-zfree", "DiscoSyn3-NL", "Random3-NL-zfree", "DiscoSyn4-L-reward",
                     "DiscoSyn3-L-reward-res0.3r150"]
  # the paper's row of today's default start, and of nothing else
  assert report.paper_row(Method.parse("DiscoSyn3-L-reward")) == "DiscoSyn3-L"
  assert report.paper_row(Method.parse("DiscoSyn3-L-reward-res0.3r150")) == "DiscoSyn3-L-reward-res0.3r150"
