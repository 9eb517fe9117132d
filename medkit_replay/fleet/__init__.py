"""Fleets: every recording under some folders replayed as its own run, then compared.

``discover`` finds the recordings, ``run`` replays each one (``run_one``) into a small
:class:`RunSummary`, ``workers`` runs them in processes and ``cluster`` on a Dask cluster,
``stats`` builds the fleet table and the cross-run statistics, ``report`` writes them (CSV,
JSON, HTML) and ``terminal`` shows them.

Importing this package is cheap (no pandas): worker processes import ``fleet.workers`` and
``fleet.run`` only.
"""

from __future__ import annotations

from medkit_replay.fleet.discover import discover
from medkit_replay.fleet.run import RunSummary, run_one

__all__ = ["RunSummary", "discover", "run_one"]
