"""Recorded messages and correlation rules as story lines and as JSON values.

Text from a recording stays as it was here (quoted); escaping is the renderer's job.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.explaining.lines import Line, join, part

if TYPE_CHECKING:
    from medkit_replay.explaining.lines import JSON
    from medkit_replay.trace import RecordedMessage, RuleFacts


def _value(value: str | int | tuple[int, str]) -> str:
    """A recorded field for a line: text quoted (it is the recording's), numbers as they are."""
    if isinstance(value, tuple):
        return f"{value[0]} ({value[1]})"
    return repr(value) if isinstance(value, str) else str(value)


def message_lines(message: RecordedMessage | None, inputs: tuple[str, ...]) -> list[Line]:
    """A recorded message: its type and topic, its fields, its key/value pairs or goals."""
    if message is None:
        return []
    where = f" in {inputs[message.input_index]}" if len(inputs) > 1 else ""
    head = [part("recorded ", "dim"), part(message.type, "dim")]
    if message.topic:
        head += [part(" on ", "dim"), part(message.topic, "topic")]
    head.append(part(where, "dim"))
    lines: list[Line] = [tuple(head)]
    if message.fields:
        pieces: list[Line] = [
            (part(f"{name} ", "dim"), part(_value(v), "text")) for name, v in message.fields
        ]
        lines.append(join(pieces, ", "))
    if message.items:
        pieces = [
            (part(key, "text"), part("=", "dim"), part(value, "text"))
            for key, value in message.items
        ]
        if message.items_left_out:
            pieces.append((part(f"+{message.items_left_out} more", "dim"),))
        lines.append(join(pieces, ", "))
    return lines


def message_fields(message: RecordedMessage | None) -> JSON:
    """A recorded message as JSON (a named constant as ``{value, name}``)."""
    if message is None:
        return None
    return {
        "input_index": message.input_index,
        "topic": message.topic,
        "type": message.type,
        "fields": {
            name: ({"value": v[0], "name": v[1]} if isinstance(v, tuple) else v)
            for name, v in message.fields
        },
        "items": [[key, value] for key, value in message.items],
        "items_left_out": message.items_left_out,
    }


def rule_text(rule: RuleFacts | None) -> str:
    """``rule ID (MODE, window N ms)``."""
    if rule is None:
        return "an unknown rule"
    return f"rule {rule.rule_id} ({rule.mode}, window {rule.window_ms} ms)"


def rule_fields(rule: RuleFacts | None) -> JSON:
    """A rule's settings as JSON."""
    if rule is None:
        return None
    return {
        "rule_id": rule.rule_id,
        "name": rule.name,
        "mode": rule.mode,
        "window_ms": rule.window_ms,
        "mute_symptoms": rule.mute_symptoms,
        "auto_clear_with_root": rule.auto_clear_with_root,
        "min_count": rule.min_count,
        "show_as_single": rule.show_as_single,
        "representative": rule.representative,
    }
