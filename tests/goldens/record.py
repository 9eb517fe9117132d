"""Record the goldens: the SHA-256 of every golden case's JSON report, as this checkout writes it.

Run from the repository root, only when a report is meant to change:
``python -m tests.goldens.record``.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

from medkit_replay.cli import main
from tests.goldens.cases import GOLDENS, ROOT, argv, cases


def report_digest(inputs: list[str], configs: list[str]) -> str:
    """Run one case in-process from the repository root: its report's SHA-256, or its status."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp, "report.json")
        cwd = Path.cwd()
        os.chdir(ROOT)
        try:
            status = main(argv(inputs, configs, out))
        finally:
            os.chdir(cwd)
        if status != 0:
            return f"exit {status}"
        return hashlib.sha256(out.read_bytes()).hexdigest()


def record() -> None:
    digests = {case: report_digest(inputs, configs) for case, inputs, configs in cases()}
    GOLDENS.write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    sys.stderr.write(f"{len(digests)} goldens written to {GOLDENS}\n")


if __name__ == "__main__":
    record()
