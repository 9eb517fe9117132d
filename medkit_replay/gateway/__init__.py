"""ros2_medkit's gateway REST/SSE API answered from a replayed recording (``medkit-replay serve``).

Read-only: faults, discovery and bulk data at any moment of the run, from an index built once.
"""
