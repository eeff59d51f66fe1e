"""``python -m rotor.cli``: the ``rotor`` command."""

import sys

from .app import command

sys.exit(command())
