"""The HTML report's evidence section: each fault's freeze frame and links to its recordings.

Values are shown as the JSON the live manager stores, cut at FRAME_CAP characters per topic.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.outputs.html_tables import esc, short, when
from medkit_replay.text import clip

if TYPE_CHECKING:
    from medkit_replay.captures import EvidenceRecording, SnapshotCapture
    from medkit_replay.outputs.html_timeline import Span
    from medkit_replay.result import Result

FRAME_CAP = 4000
"""Characters of one topic's value shown; the JSON report holds it whole."""
FAULT_CAP = 200
"""Faults given a block; the JSON report holds every capture."""


def _frame(capture: SnapshotCapture, span: Span) -> str:
    rows = "".join(
        f"<tr><td>{esc(short(t.topic))}</td><td>{esc(short(t.message_type))}</td>"
        f'<td data-v="{when(span, t.message_t_ns)[1]}">{esc(when(span, t.message_t_ns)[0])}</td>'
        f"<td><pre class=json>{esc(clip(json.dumps(t.data, indent=1), FRAME_CAP))}</pre></td></tr>"
        for t in capture.topics
    )
    body = (
        "<table class=data><thead><tr><th>topic</th><th>type</th><th>message at (s)</th>"
        f"<th>value</th></tr></thead><tbody>{rows}</tbody></table>"
        if rows
        else '<p class="empty">Nothing was sampled (no message on its topics in time).</p>'
    )
    return (
        f"<p>Freeze frame: capture {capture.capture_id} at {esc(when(span, capture.t_ns)[0])} s"
        f"{'' if capture.retained else ' (its snapshot rows would be gone by the end)'}</p>{body}"
    )


def _link(recording: EvidenceRecording, span: Span) -> str:
    name = esc(short(recording.recording_id))
    label = (
        f'<a href="{esc(Path(recording.path).absolute().as_uri())}">{name}</a>'
        if recording.path is not None
        else name
    )
    gone = (
        f" — deleted by the live manager at {esc(when(span, recording.deleted_ns)[0])} s: "
        f"{esc(short(recording.deleted_reason))}"
        if recording.deleted_ns is not None and recording.deleted_reason is not None
        else ""
    )
    return (
        f"<li>{label}: {esc(when(span, recording.start_ns)[0])} to "
        f"{esc(when(span, recording.end_ns)[0])} s, {recording.messages:,} messages, "
        f"{recording.bytes:,} bytes{gone}</li>"
    )


def evidence_section(result: Result, span: Span) -> str:
    """The section, or nothing when no capture or recording was made."""
    if not result.snapshots and not result.recordings:
        return ""
    frames = {c.fault_code: c for c in result.snapshots if c.freeze_frame}
    recordings: dict[str, list[EvidenceRecording]] = {}
    for recording in result.recordings:
        for code in recording.fault_codes:
            recordings.setdefault(code, []).append(recording)
    codes = sorted(set(frames) | set(recordings), key=lambda c: c.encode("utf-8"))
    blocks = []
    for code in codes[:FAULT_CAP]:
        parts = [f'<h3 class="code">{esc(short(code))}</h3>']
        if code in frames:
            parts.append(_frame(frames[code], span))
        if code in recordings:
            links = "".join(_link(r, span) for r in recordings[code])
            parts.append(f"<p>Black-box recordings:</p><ul>{links}</ul>")
        blocks.append(f'<div class="evidence">{"".join(parts)}</div>')
    more = (
        f'<p class="cap-note">Showing {FAULT_CAP} of {len(codes):,} faults; the JSON report '
        "holds every capture.</p>"
        if len(codes) > FAULT_CAP
        else ""
    )
    notes = "".join(f"<li>{esc(short(n, 600))}</li>" for n in result.evidence_notes)
    return (
        f'<section id="evidence"><h2>Evidence <span class="count">({len(result.snapshots):,} '
        f"captures, {len(result.recordings):,} recordings)</span></h2>"
        + (f"<ul>{notes}</ul>" if notes else "")
        + more
        + "".join(blocks)
        + "</section>"
    )
