"""``python -m rotor.cli``: the ``rotor`` command."""

import sys

from .app import main

sys.exit(main())
