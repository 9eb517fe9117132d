"""Explaining one fault: its story from the one replay, for people and as JSON records.

``build_story`` turns a Result and the FaultTrace the replay filled into a Story; ``terminal``
draws it, ``records`` writes it as JSON; ``nearest_codes`` helps when a code never appeared.
"""

from medkit_replay.explaining.lines import Entry
from medkit_replay.explaining.nearest import known_codes, nearest_codes
from medkit_replay.explaining.records import EXPLAIN_SCHEMA, story_record, write_story_json
from medkit_replay.explaining.story import Story, build_story
from medkit_replay.explaining.terminal import print_story, render_story

__all__ = [
    "EXPLAIN_SCHEMA",
    "Entry",
    "Story",
    "build_story",
    "known_codes",
    "nearest_codes",
    "print_story",
    "render_story",
    "story_record",
    "write_story_json",
]
