"""Synergy files a user hands us: each damaged or odd one is refused in one line naming the
file and what is wrong (Python: SynergyFileError; the command line: exit 2, nothing made),
and a good one loads the same whatever happened around it; exports are written whole, with
the user's umask, and never onto a folder or an empty name."""

import io
import json
import os
import random
import zipfile

import numpy as np
import pytest

import discosyn_jax as ds
from discosyn import cli
from discosyn_jax.synergies import artefact, fitting
from tests import helpers

RECORD = os.path.join(helpers.ROOT, "docs/results/paper/discosyn3-l-reward-set1-seed0")
SHIPPED = fitting.SHIPPED / "shadow20-set1.npz"


def rewritten(tmp_path, name="mine.npz", meta=None, **arrays):
  """shadow20-set1 rewritten with its meta and arrays changed as given."""
  with np.load(SHIPPED) as data:
    found = {k: data[k] for k in data.files}
  info = json.loads(str(found.pop("meta")))
  info.update(meta or {})
  found.update(arrays)
  path = tmp_path / name
  np.savez(path, meta=np.array(json.dumps(info)), **found)
  return path


def refused(path, match):
  with pytest.raises(artefact.SynergyFileError, match=match) as err:
    ds.Synergies.load(path)
  assert "\n" not in str(err.value) and str(path.name) in str(err.value)


def test_a_truncated_or_damaged_archive_is_refused_naming_the_file(tmp_path):
  data = SHIPPED.read_bytes()
  (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
  refused(tmp_path / "cut.npz", "cut.npz is not a synergy file")
  # a member whose CRC fails: one byte of the stored data flipped
  damaged = bytearray(data)
  with zipfile.ZipFile(io.BytesIO(data)) as archive:
    info = archive.getinfo("synergies.kernel.npy")
  spot = info.header_offset + 30 + len(info.filename) + len(info.extra) + info.compress_size - 3
  damaged[spot] ^= 0xFF
  (tmp_path / "crc.npz").write_bytes(bytes(damaged))
  refused(tmp_path / "crc.npz", "damaged or unreadable")
  (tmp_path / "text.npz").write_text("W = [[1, 2], [3, 4]]\n")
  refused(tmp_path / "text.npz", "not an .npz archive")


def test_non_finite_or_non_numeric_synergies_are_refused(tmp_path):
  with np.load(SHIPPED) as data:
    kernel = data["synergies.kernel"].copy()
  for value, name in ((np.nan, "nan.npz"), (np.inf, "inf.npz")):
    bad = kernel.copy()
    bad[1, 4] = value
    refused(rewritten(tmp_path, name, **{"synergies.kernel": bad}), "NaN or infinite values")
  refused(rewritten(tmp_path, "words.npz", **{"synergies.kernel": np.full(kernel.shape, "a")}),
          "not numbers")


def test_actuators_in_another_order_are_named_as_such(tmp_path):
  meta = json.loads(str(np.load(SHIPPED)["meta"]))
  hand = dict(meta["hand"])
  hand["actuators"] = hand["actuators"][1:] + hand["actuators"][:1]
  path = rewritten(tmp_path, "shuffled.npz", meta={"hand": hand})
  config = ds.TrainConfig(tasks=("valve_cw",), decoder_from=str(path), freeze_decoder=True,
                          alpha2=0.0, alpha3=0.0)
  with pytest.raises(ValueError, match="shuffled.npz drives the shadow20 hand's actuators in "
                                       "another order"):
    fitting.load_decoder(path, config)


def test_decode_with_the_wrong_length_is_refused_before_jax():
  syn = ds.Synergies.load("shadow20-set1")
  assert syn.decode(np.zeros(syn.b)).shape == (20,)
  with pytest.raises(ValueError, match="z must end in the decoder's 3 synergy activations, not "
                                       r"shape \(4,\)"):
    syn.decode(np.zeros(4))


def test_an_export_is_whole_readable_as_the_umask_says_and_never_onto_a_folder(tmp_path, capsys):
  old = os.umask(0o022)
  try:
    path = artefact.export(RECORD, tmp_path / "mine.npz")
  finally:
    os.umask(old)
  assert (path.stat().st_mode & 0o777) == 0o644
  (tmp_path / "folder").mkdir()
  with pytest.raises(ValueError, match="a folder is there"):
    artefact.export(RECORD, tmp_path / "folder")
  assert sorted(p.name for p in tmp_path.iterdir()) == ["folder", "mine.npz"]  # no temp left
  code = cli.main(["synergies", RECORD, "--export", ""])
  err = [l for l in capsys.readouterr().err.splitlines() if l]
  assert code == 2 and len(err) == 1 and "--export needs a file name" in err[0], err


def test_random_damage_either_loads_the_same_or_is_refused_cleanly(tmp_path):
  """Bytes flipped and cuts at random points of a good file: each either loads the very
  same decoder (a byte the archive does not read) or is refused in one line; nothing else."""
  good = SHIPPED.read_bytes()
  want = ds.Synergies.load(SHIPPED)
  rng = random.Random(0)
  outcomes = {"same": 0, "refused": 0}
  for trial in range(60):
    path = tmp_path / f"t{trial}.npz"
    path.write_bytes(helpers.damaged(good, trial, rng))
    try:
      got = ds.Synergies.load(path)
    except artefact.SynergyFileError as err:
      assert "\n" not in str(err) and path.name in str(err)
      outcomes["refused"] += 1
      continue
    assert got.meta == want.meta
    np.testing.assert_array_equal(_flat(got.params), _flat(want.params))
    outcomes["same"] += 1
  assert outcomes["refused"] > 0


def _flat(tree):
  if isinstance(tree, dict):
    return np.concatenate([_flat(tree[k]).ravel() for k in sorted(tree)])
  return np.asarray(tree).ravel()
