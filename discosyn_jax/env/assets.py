"""Where the MJCF files live, in a checkout and in an installed package alike."""

from __future__ import annotations

import functools
import pathlib


@functools.cache
def xml_dir() -> pathlib.Path:
  """The folder holding arena.xml, hands/ and objects/.

  A checkout (or an editable install) reads the repository's top-level `xml/`;
  a wheel carries the same files as the package data `discosyn_jax/xml/`.
  """
  package = pathlib.Path(__file__).resolve().parents[1]  # discosyn_jax/
  for candidate in (package / "xml", package.parent / "xml"):
    if (candidate / "arena.xml").is_file():
      return candidate
  raise FileNotFoundError(
      f"arena.xml not found beside {package}: the package was installed without its XML files"
  )


def xml_path(name: str) -> pathlib.Path:
  path = xml_dir() / name
  if not path.is_file():
    raise FileNotFoundError(f"no MJCF file {name!r} in {xml_dir()}")
  return path
