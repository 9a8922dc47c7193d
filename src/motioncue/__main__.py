"""``python -m motioncue``: the same as the ``motioncue`` command."""

from motioncue.cli import console

console()
