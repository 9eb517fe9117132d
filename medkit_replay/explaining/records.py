"""A fault's story as strict JSON records (``explain --json``): the same entries, as data.

Deterministic: same inputs and config, same bytes. ASCII only, so no recorded character can
act on a terminal the JSON is printed on.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, TextIO

from medkit_replay.version import __version__

if TYPE_CHECKING:
    from medkit_replay.explaining.lines import JSON
    from medkit_replay.explaining.story import Story

EXPLAIN_SCHEMA = "medkit-replay/explain/v1"
"""Schema of the records; fields are listed in the README's ``explain`` section."""


def story_record(story: Story) -> dict[str, JSON]:
    """The story as one JSON object: the recording, a summary, every entry, the final state."""
    return {
        "schema": EXPLAIN_SCHEMA,
        "tool_version": __version__,
        "upstream_release": story.upstream_release,
        "fault_code": story.fault_code,
        "recording": {
            "inputs": list(story.inputs),
            "start_ns": story.origin_ns,
            "end_ns": story.end_ns,
        },
        "at_ns": story.at_ns,
        "at_offset_ns": story.at_ns - story.origin_ns if story.at_ns is not None else None,
        "summary": story.summary,
        "entries": [entry.fields for entry in story.entries],
        "state": story.state_fields,
    }


def write_story_json(story: Story, stream: TextIO) -> None:
    """Write the story's JSON (indented, ASCII, no NaN) and a final newline."""
    stream.write(json.dumps(story_record(story), indent=2, ensure_ascii=True, allow_nan=False))
    stream.write("\n")
