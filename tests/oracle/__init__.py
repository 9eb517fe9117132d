"""Straightforward implementations kept as oracles for the product's one fast path.

Test code only: nothing in ``medkit_replay`` imports this package.
"""
