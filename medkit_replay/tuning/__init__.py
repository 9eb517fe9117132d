"""Tuning the fault manager with recordings: what-if sweeps over its settings, and correlation
rules learned from a fleet.

``grid`` builds the variants from ``--vary`` specs; ``fanout`` drives one manager per variant
from a single pass over a recording; ``metrics`` measures each as its records are made;
``run`` is one job (an input and a share of the grid), ``sweep`` runs them all (processes or
Dask, as a fleet does) and streams the ``tables``; ``ranking`` sums them up, ``terminal`` and
``page`` show them. For ``suggest-rules``: ``observe`` replays each input (its confirmations, or
its mutes under proposed rules), ``suggest`` proposes correlation rules, ``rules_file`` writes
them. Nothing is imported here, so ``suggest-rules --help`` loads ``suggest`` alone.
"""
