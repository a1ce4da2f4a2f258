"""Top layer: ``python -m rbhyst``, the command line."""

from rbhyst.cli import entry

entry()
