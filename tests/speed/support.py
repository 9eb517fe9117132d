"""What the fast-path tests share: the recordings to compare and a field-by-field view of messages.

The replay (generated decoders, reading by MCAP message index, bridges reporting field by field,
the manager recording rows) must conclude what the plain oracle (tests/oracle/replay.py:
rosbags, whole chunks, request and record objects) concludes.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from medkit_replay.inputs.cdr.decoders import DiagnosticArrayView
from medkit_replay.inputs.ros1.decoders import Ros1DiagnosticArrayView
from medkit_replay.outputs.json_report import dumps
from medkit_replay.pipeline import replay
from tests.oracle.replay import ENGINE_SECTIONS, oracle_sections

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = sorted(p for p in (ROOT / "sample_bags").iterdir() if p.suffix not in {".md", ".py"})
FIXTURES_DIR = ROOT / "tests" / "fixtures" / "rosbag2"
FIXTURES = sorted(
    p for p in FIXTURES_DIR.iterdir() if p.is_dir() and p.name != "bare_files"
) + sorted((FIXTURES_DIR / "bare_files").iterdir())
RULES = ROOT / "rules" / "nav2"


def plain(value: object) -> object:
    """A message as nested plain values: what its fields hold, whatever class carries them.

    rosbags' classes also carry their constants as fields; those are left out (the light
    records have them as class attributes).
    """
    if isinstance(value, DiagnosticArrayView | Ros1DiagnosticArrayView):  # built on demand
        return {"header": plain(value.header), "status": plain(value.status)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if not f.name.isupper() and not f.name.startswith("__")
        }
    if isinstance(value, list):
        return [plain(item) for item in value]
    if isinstance(value, np.ndarray):
        return ("array", str(value.dtype), value.tolist())
    return (type(value).__name__, value)


def report_both_ways(
    inputs: list[Path], configs: list[Path]
) -> tuple[dict[str, object], dict[str, object]]:
    """The engine's report sections from the oracle and from the replay (as its JSON says)."""
    report = json.loads(dumps(replay(inputs, configs)))
    fast = {key: report[key] for key in ENGINE_SECTIONS}
    return oracle_sections(inputs, configs), fast
