"""Synergy models outside DiscoSyn: the sequential baselines' PCA and autoencoder, fitted to
the actions of trained policies, and the one way decoders are loaded into a run.

A fitted model is written as a *synergy file* (.npz): the decoder's parameters, in exactly
the layout of DiscoSyn's own decoder (linear: `synergies.kernel` (k, 20) and
`synergies.bias`; mlp: networks.GaussianHead's), plus a JSON `meta` entry with the config
fields the decoder needs (decoder, n_synergies, decoder_hidden) and its explained variance.
A run directory works as a source too: its latest checkpoint's decoder, or where its
checkpoints are not kept (a run's record, discosyn_jax/experiments/record.py) its decoder.npz;
and so does the NAME of a synergy file that ships with the package (SHIPPED, artefact.py).

Both fitted decoders take z on a unit scale: PCA's components are scaled by the standard
deviation along them, the autoencoder's latent code is standardised and the scaling is
folded into the decoder's first layer. A policy head that starts with std 1 then explores
about one data standard deviation along every synergy.
"""

from __future__ import annotations

import json
import os
import pathlib
import tempfile
import zipfile
import zlib
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax

from discosyn_jax import decoders
from discosyn_jax.agent import networks
from discosyn_jax.checks import BadInput

ARCHITECTURE = ("decoder", "n_synergies", "decoder_bias", "decoder_hidden", "squash_z")
EVERY_KIND = ("decoder", "n_synergies", "squash_z")  # the rest a kind names (DecoderKind.fields)
_DEFAULTS = {"squash_z": False}  # fields added since the first synergy files were written


def architecture(fields: dict[str, Any]) -> dict[str, Any]:
  """The ARCHITECTURE fields of a meta or a dict of config fields, defaults filled in."""
  fields = {**_DEFAULTS, **fields}
  return {k: fields[k] for k in ARCHITECTURE}


def described(fields: dict[str, Any]) -> dict[str, Any]:
  """What a synergy file says of its decoder: its ARCHITECTURE, and `task_noise` where the
  run's tasks each had their own noise (the decoder's own noise was then never trained)."""
  return {**architecture(fields), **({"task_noise": True} if fields.get("task_noise") else {})}


def meta_of(config) -> dict[str, Any]:
  """A run's decoder as a synergy file's meta: what `described` says of it and its start
  (the start names the rows that freeze it, experiments/method.py)."""
  fields = {k: getattr(config, k) for k in (*ARCHITECTURE, "task_noise")}
  return {**described(fields), "decoder_init": config.decoder_init}
_RUN_DECODER = "params.params.synergy_decoder."


def applied_actions(rollouts: dict[str, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
  """{task: (samples, action_size)}: the actions the envs applied (clipped to [-1, 1]) at
  the steps of `Trainer.rollouts` where the episode was still running."""
  out = {}
  for name, traj in rollouts.items():
    alive = np.asarray(traj["alive"]) > 0
    out[name] = np.clip(np.asarray(traj["action"])[alive], -1.0, 1.0)
  return out


def explained_variance(actions: np.ndarray, reconstructed: np.ndarray) -> float:
  """The fraction of the actions' total variance (about their mean) a reconstruction explains."""
  total = np.sum((actions - actions.mean(axis=0)) ** 2)
  return float(1.0 - np.sum((actions - reconstructed) ** 2) / total)


def _residual_log_std(actions, reconstructed):
  # what a Gaussian p(a|z) fitted to the data would have; unused by noiseless baselines
  return np.log(np.maximum((actions - reconstructed).std(axis=0), 1e-3)).astype(np.float32)


def fit_pca(actions: np.ndarray, k: int) -> tuple[dict, float]:
  """A linear decoder a = mean + z (sqrt(var_i) v_i) from the top-k principal components,
  and the fraction of variance they explain (the sum of their eigenvalue fractions)."""
  from sklearn.decomposition import PCA

  _check_k(k, actions)
  pca = PCA(n_components=k).fit(actions)
  kernel = (pca.components_ * np.sqrt(pca.explained_variance_)[:, None]).astype(np.float32)
  bias = pca.mean_.astype(np.float32)
  reconstructed = pca.inverse_transform(pca.transform(actions))
  params = {"synergies": {"kernel": kernel, "bias": bias},
            "log_std": _residual_log_std(actions, reconstructed)}
  return params, float(np.sum(pca.explained_variance_ratio_))


class Autoencoder(nn.Module):
  """a -> z (k) -> a; the decoder half is the module DiscoSyn's mlp decoder uses."""
  k: int
  hidden: tuple[int, ...]
  action_size: int

  def setup(self):
    self.encoder = networks.MLP(self.hidden, self.k)
    self.decoder = networks.GaussianHead(self.hidden, self.action_size, 1.0, out_scale=1.0)

  def encode(self, a):
    return self.encoder(a)

  def __call__(self, a):
    return self.decoder(self.encoder(a))[0]


def fit_autoencoder(actions: np.ndarray, k: int, hidden=(128, 128), steps: int = 3000,
                    batch: int = 256, learning_rate: float = 1e-3, seed: int = 0) -> tuple[dict, float]:
  """An MLP autoencoder with a k-dimensional code, trained by Adam on the reconstruction
  error; its decoder (code standardised) and the fraction of variance it explains."""
  _check_k(k, actions)
  data = jnp.asarray(actions, jnp.float32)
  model = Autoencoder(k, tuple(hidden), data.shape[1])
  init_key, key = jax.random.split(jax.random.PRNGKey(seed))
  params = model.init(init_key, data[:1])
  optimizer = optax.adam(learning_rate)

  def loss(p, x):
    return jnp.mean((model.apply(p, x) - x) ** 2)

  def step(carry, key):
    p, opt = carry
    x = data[jax.random.randint(key, (min(batch, data.shape[0]),), 0, data.shape[0])]
    value, grads = jax.value_and_grad(loss)(p, x)
    updates, opt = optimizer.update(grads, opt, p)
    return (optax.apply_updates(p, updates), opt), value

  train = jax.jit(lambda p, o, keys: jax.lax.scan(step, (p, o), keys))
  (params, _), _ = train(params, optimizer.init(params), jax.random.split(key, steps))

  code = np.asarray(model.apply(params, data, method=Autoencoder.encode))
  mean, std = code.mean(axis=0), np.maximum(code.std(axis=0), 1e-6)
  decoder = standardised_input(params["params"]["decoder"], mean, std)
  reconstructed = np.asarray(model.apply(params, data))
  decoder["log_std"] = _residual_log_std(actions, reconstructed)
  return decoder, explained_variance(actions, reconstructed)


def standardised_input(decoder: dict, mean: np.ndarray, std: np.ndarray) -> dict:
  """An MLP decoder's params (GaussianHead layout) taking z = (code - mean) / std instead
  of the code: decoder(mean + std * z), the scaling folded into its first layer."""
  decoder = jax.tree.map(np.asarray, decoder)
  first = decoder["MLP_0"]["Dense_0"]
  first["bias"] = (first["bias"] + mean @ first["kernel"]).astype(np.float32)
  first["kernel"] = (std[:, None] * first["kernel"]).astype(np.float32)
  return decoder


def _decoder_model(fields: dict[str, Any], params: dict) -> networks.DiscoSyn:
  """A module around the decoder described by `fields` (ARCHITECTURE) with these params."""
  from discosyn_jax.config import TrainConfig

  config = TrainConfig(**architecture(fields))
  action_size = int(np.shape(params["log_std"])[-1])
  return networks.build(config, obs_sizes=(1,), action_size=action_size)


def decode(fields: dict[str, Any], params: dict, z: np.ndarray) -> np.ndarray:
  """The decoder's mean at z, for a decoder described by `fields` (ARCHITECTURE); BadInput
  where z's last axis is not the decoder's b."""
  b = int(fields["n_synergies"])
  if np.ndim(z) < 1 or np.shape(z)[-1] != b:
    raise BadInput(f"z must end in the decoder's {b} synergy activations, not shape {np.shape(z)}")
  model = _decoder_model(fields, params)
  return np.asarray(model.apply({"params": {"synergy_decoder": params}}, jnp.asarray(z),
                                method=networks.DiscoSyn.decode)[0])


def basis(fields: dict[str, Any], params: dict) -> np.ndarray:
  """The (action_size, b) synergy basis of a decoder (diagnostics.synergy_basis: the linear
  decoder's W, an MLP decoder's Jacobian at z = 0)."""
  from discosyn_jax.synergies import diagnostics

  model = _decoder_model(fields, params)
  return np.asarray(diagnostics.synergy_basis(model, {"params": {"synergy_decoder": params}}))


def in_subspace_of(learned: dict, start: dict) -> dict:
  """A linear decoder with the learned one's scale, offset and noise in the subspace of
  `start`: with the learned basis W = U S V^T (action_size, b) and U0 the left singular
  vectors of start's, W' = U0 S V^T; bias and log std are the learned ones."""
  u, s, vt = np.linalg.svd(np.asarray(learned["synergies"]["kernel"], np.float64).T,
                           full_matrices=False)
  u0 = np.linalg.svd(np.asarray(start["synergies"]["kernel"], np.float64).T,
                     full_matrices=False)[0]
  out = jax.tree.map(lambda x: np.asarray(x, np.float32), learned)
  out["synergies"]["kernel"] = ((u0 * s) @ vt).T.astype(np.float32)
  return out


def _check_k(k: int, actions: np.ndarray):
  if not 1 <= k <= min(actions.shape):
    raise BadInput(f"cannot fit {k} synergies to {actions.shape[0]} actions of size "
                   f"{actions.shape[1]}")


# -- synergy files -------------------------------------------------------------
SHIPPED = pathlib.Path(__file__).resolve().parent / "shipped"  # NAME.npz, NAME.png


def shipped_name(source) -> bool:
  """Whether `source` names a shipped synergy file rather than a path."""
  return (isinstance(source, str) and "/" not in source and not pathlib.Path(source).exists()
          and (SHIPPED / f"{source}.npz").is_file())


def resolve(source: str | pathlib.Path) -> pathlib.Path:
  """The path of a synergy file or run folder, or of the shipped file named `source`."""
  return SHIPPED / f"{source}.npz" if shipped_name(source) else pathlib.Path(source)


def save(path: pathlib.Path, params: dict, fields: dict[str, Any], **meta) -> pathlib.Path:
  """Write a synergy file (atomically: a crash leaves no half-written file)."""
  path = pathlib.Path(path)
  if not path.name or path.is_dir():
    raise BadInput(f"cannot write a synergy file to {str(path) or 'an empty path'}: "
                   f"{'a folder is there' if path.is_dir() else 'no file name'}")
  path.parent.mkdir(parents=True, exist_ok=True)
  flat = {".".join(str(getattr(k, "key", k)) for k in keys): np.asarray(leaf)
          for keys, leaf in jax.tree_util.tree_flatten_with_path(params)[0]}
  info = {**described(fields), **meta}
  fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz")
  try:
    with os.fdopen(fd, "wb") as f:
      np.savez(f, meta=np.array(json.dumps(info)), **flat)
    umask = os.umask(0)  # read the user's umask (mkstemp's file is 0600 whatever it is)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)
  except BaseException:
    pathlib.Path(tmp).unlink(missing_ok=True)  # nothing half-written left beside it
    raise
  return path


def read(path: str | pathlib.Path) -> tuple[dict[str, Any], dict]:
  """(meta with the decoder's config fields, decoder params) of a synergy file, a run, or a
  shipped synergy file's name."""
  path = resolve(path)
  if path.is_dir():
    from discosyn_jax.run import checkpoints, layout, reading

    kept = path / layout.DECODER_FILE
    if kept.is_file() and not checkpoints.candidates(path):  # a record without checkpoints
      return read(kept)
    config, _, flat = reading.newest(path, lambda c: checkpoints.read_arrays(c, _RUN_DECODER))
    if config.kind.full_action:
      raise BadInput(f"{path} is a full-action run: it has no synergy decoder")
    meta = meta_of(config)
  elif path.is_file():
    if not zipfile.is_zipfile(path):  # a text file, an image: np.load would talk of pickles
      raise BadInput(f"{path} is not a synergy file: not an .npz archive")
    try:
      with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["meta"]))
        flat = {k: data[k] for k in data.files if k != "meta"}
    except KeyError:
      raise BadInput(f"{path} is not a synergy file: it holds no meta") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as err:
      # a truncated archive, a member whose CRC fails, meta that is not JSON
      raise BadInput(f"{path} is not a synergy file: damaged or unreadable "
                     f"({type(err).__name__}: {err})") from None
    _check_file(path, meta, flat)
  else:
    names = ", ".join(sorted(p.stem for p in SHIPPED.glob("*.npz")))
    raise BadInput(f"decoder source {path} does not exist, and no shipped synergies have that "
                   f"name (shipped: {names})")
  meta = {**_DEFAULTS, **meta}
  meta["decoder_hidden"] = tuple(meta["decoder_hidden"])
  params: dict = {}
  for name, value in flat.items():
    node = params
    *parents, leaf = name.split(".")
    for part in parents:
      node = node.setdefault(part, {})
    node[leaf] = np.asarray(value, np.float32)
  return meta, params


def _check_file(path, meta, flat: dict) -> None:
  """A synergy file holds the decoder its meta describes, every array in its shape: one
  line naming the first thing that differs (before any run folder is made)."""
  from discosyn_jax.config import TrainConfig

  fields = {**_DEFAULTS, **meta} if isinstance(meta, dict) else {}
  missing = [k for k in ARCHITECTURE if k not in fields]
  if missing:
    raise BadInput(f"{path} is not a synergy file: its meta has no {missing[0]}")
  try:
    config = TrainConfig(**{k: tuple(v) if isinstance(v, list) else v  # JSON has no tuples
                            for k, v in architecture(fields).items()}).validate()
  except (TypeError, ValueError) as err:
    raise BadInput(f"{path} is not a synergy file: {err}") from None
  # the hand's 20 actuators, unless the file's noise says otherwise (a malformed one: its
  # shape is then named below)
  action_size = np.shape(flat["log_std"])[-1] if np.ndim(flat.get("log_std", 0)) else 20
  model = networks.build(config, obs_sizes=(1,), action_size=action_size)
  shapes = jax.eval_shape(model.init, jax.random.PRNGKey(0), [jnp.zeros((1, 1))])
  want = {".".join(str(k.key) for k in keys): tuple(leaf.shape) for keys, leaf in
          jax.tree_util.tree_flatten_with_path(shapes["params"]["synergy_decoder"])[0]}
  have = {k: tuple(np.shape(v)) for k, v in flat.items()}
  for name in sorted(set(want) | set(have)):
    if want.get(name) != have.get(name):
      raise BadInput(f"{path} does not hold the {config.decoder} decoder its meta describes: "
                     f"{name} is {have.get(name, 'absent')} there, {want.get(name, 'absent')} "
                     f"for that decoder")
  for name, value in sorted(flat.items()):
    if not np.issubdtype(np.asarray(value).dtype, np.number):
      raise BadInput(f"{path} is not a synergy file: {name} holds {np.asarray(value).dtype}, "
                     "not numbers")
    if not np.isfinite(value).all():
      raise BadInput(f"{path} is not a synergy file: {name} holds NaN or infinite values")


def load_decoder(path, config) -> dict:
  """The decoder params of `path` for a run of `config`; BadInput in one line when the
  decoder is not the one the config describes, or drives another hand."""
  meta, params = read(path)
  hand = meta.get("hand")  # a synergy file of format 2 names the actuators it drives
  if hand:
    from discosyn_jax.env import hands

    wanted = tuple(hands.actuators(config.hand))
    if tuple(hand["actuators"]) != wanted and sorted(hand["actuators"]) == sorted(wanted):
      raise BadInput(f"{path} drives the {hand['name']} hand's actuators in another order than "
                     f"{hands.label(config.hand)}'s action order: its decoder's rows would "
                     "move the wrong joints")
    if tuple(hand["actuators"]) != wanted:
      raise BadInput(f"{path} drives the {hand['name']} hand ({len(hand['actuators'])} "
                     f"actuators), not {hands.label(config.hand)} "
                     f"({len(hands.actuators(config.hand))} actuators)")
  for name in ARCHITECTURE:
    if name not in EVERY_KIND and name not in decoders.kind(meta["decoder"]).fields:
      continue
    if meta[name] != getattr(config, name):
      raise BadInput(f"the decoder in {path} has {name} = {meta[name]!r}, the config asks for "
                     f"{getattr(config, name)!r}")
  return params


def frozen_fields(meta: dict[str, Any], path) -> dict[str, Any]:
  """The TrainConfig fields of a run in the frozen synergy space of `path` (its `meta` as
  `read` gives it): the decoder's architecture, frozen, no discriminator bonus and no
  decoder entropy (constants here). Fitted PCA / autoencoder spaces act with their mean
  (no noise outside the space); a DiscoSyn decoder keeps the noise it learned, or, where its
  tasks each learned their own (`task_noise`), each new task learns its own."""
  source = str(path) if shipped_name(path) else str(pathlib.Path(path).resolve())
  return dict(architecture(meta), decoder_from=source, task_noise=bool(meta.get("task_noise")),
              freeze_decoder=True, decoder_noise="method" not in meta, alpha2=0.0, alpha3=0.0,
              decoder_weight_decay=0.0, decoder_weight_decay_steps=0, decoder_init="random")

