"""Helpers for the HTML report tests: scripts written in tmp_path, a page parser, the embedded data.

The parser is the standard library's, which treats <script> content as raw text exactly as a
browser does, so a description that broke out of the data block would show up as extra tags.
"""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.pipeline import replay

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
SEC = 1_000_000_000
MS = 1_000_000

Attrs = dict[str, str | None]


def example_result() -> Result:
    """The bundled Nav2 mission script under the Nav2 rules."""
    return replay([EXAMPLE], [NAV2])


def write_script(path: Path, lines: list[dict[str, object]]) -> Path:
    """A JSON-lines script at path."""
    path.write_text("".join(json.dumps(line) + "\n" for line in lines), encoding="utf-8")
    return path


def report(t_ns: int, code: str, event: str, **fields: object) -> dict[str, object]:
    """One ``op: report`` line."""
    return {
        "t_ns": t_ns,
        "op": "report",
        "fault_code": code,
        "event_type": event,
        "source_id": "/src",
        **fields,
    }


class Page(HTMLParser):
    """Every start tag with its attributes, and the text of each <script>."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, Attrs]] = []
        self.scripts: list[tuple[Attrs, str]] = []
        self._script: Attrs | None = None
        self._chunks: list[str] = []
        self.feed(text)
        self.close()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))
        if tag == "script":
            self._script = dict(attrs)
            self._chunks = []

    def handle_data(self, data: str) -> None:
        if self._script is not None:
            self._chunks.append(data)

    def handle_endtag(self, tag: str) -> None:
        if tag == "script" and self._script is not None:
            self.scripts.append((self._script, "".join(self._chunks)))
            self._script = None

    def with_class(self, name: str) -> list[Attrs]:
        """Attributes of every element whose class list holds name."""
        return [a for _, a in self.tags if name in (a.get("class") or "").split()]

    def by_id(self, element_id: str) -> Attrs | None:
        """Attributes of the element with that id."""
        return next((a for _, a in self.tags if a.get("id") == element_id), None)

    def data(self) -> dict[str, object]:
        """The JSON the page's script reads."""
        raw = next(text for a, text in self.scripts if a.get("id") == "medkit-data")
        value: dict[str, object] = json.loads(raw)
        return value

    def lanes(self) -> list[dict[str, object]]:
        """The per-row data."""
        lanes = self.data()["lanes"]
        assert isinstance(lanes, list)
        return lanes


LONG_MISSION_S = 1800
"""Bag time of the generated long mission: half an hour at 10 Hz per fault."""


def long_mission(folder: Path) -> Result:
    """A generated long mission, dense enough to make the page down-sample every series.

    ``DENSE``: a report every 100 ms, FAILED (each a ``fault_updated`` on the confirmed fault)
    but for two bursts of PASSED every 150 s that heal it twice within 2.4 s (dozens of status
    changes, confirmed and cleared events close together). ``FLAPPY``: confirms and
    heals every 8 s (hundreds of status periods). ``QUIET``: one FAILED report.
    """
    config = folder / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n"
        "    healing_enabled: true\n    healing_threshold: 3\n",
        encoding="utf-8",
    )
    lines = [report(MS // 2, "QUIET", "FAILED", severity=3)]
    for tick in range(LONG_MISSION_S * 10):
        t_ns = tick * 100 * MS + MS
        burst = tick % 1500 < 8 or 16 <= tick % 1500 < 24  # heal, confirm, heal within 2.4 s
        lines.append(report(t_ns, "DENSE", "PASSED" if burst else "FAILED", severity=2))
        if tick % 5 == 0:
            flap = "FAILED" if (tick // 40) % 2 == 0 else "PASSED"
            lines.append(report(t_ns + 1, "FLAPPY", flap, severity=1))
    return replay([write_script(folder / "long.jsonl", lines)], [config])
