"""The ``rotor`` command line: a thin layer over the library, one module per command group.

:mod:`.app` assembles the parser and handles errors; :mod:`.args` holds the shared
argument types and the flag convention (``--json``, ``--plot DIR``, ``--quiet``,
``--format`` for tables only); :mod:`.output` prints summaries and JSON and writes plots.
Commands: :mod:`.engine` (table, info, plot, presets), :mod:`.run` (steady, simulate),
:mod:`.logs` (analyze), :mod:`.diagnostics` (diagnose), :mod:`.design` (flywheel),
:mod:`.demo`. Each command parses, calls the library, and prints the result's
``summary()`` or ``to_json_dict()``; it formats nothing itself.

May import: everything (the top layer). Import lazily inside the commands, so that
``rotor --help`` stays fast.
"""

from .app import command, main

__all__ = ["command", "main"]

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
