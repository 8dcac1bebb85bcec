"""``python -m springchain``: the command line."""

from ._entry import run

run()
