"""`python -m discosyn ...`: the `discosyn` command."""

from discosyn.cli import entry

entry()
