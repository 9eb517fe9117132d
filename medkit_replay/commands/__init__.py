"""Subcommands of ``medkit-replay`` beyond ``analyze``: one module per command.

Each module defines one click command; ``medkit_replay.cli`` registers it on the group.
"""
