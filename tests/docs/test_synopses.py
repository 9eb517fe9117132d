"""Each command's synopsis in docs/commands/ names every option its ``--help`` lists (a page
without a marked synopsis, such as follow's and serve's, is left to its prose)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from medkit_replay.cli import cli

ROOT = Path(__file__).resolve().parents[2]
SYNOPSIS = re.compile(r"<!-- example: synopsis -->\n```\n(.*?)```", re.DOTALL)


@pytest.mark.parametrize("name", sorted(cli.commands))
def test_the_synopsis_names_every_option(name: str) -> None:
    page = ROOT / "docs" / "commands" / f"{name}.md"
    found = SYNOPSIS.search(page.read_text(encoding="utf-8")) if page.exists() else None
    if found is None:
        pytest.skip(f"{name}: no marked synopsis")
    options = [o for param in cli.commands[name].params for o in param.opts if o.startswith("--")]
    missing = [o for o in options if not re.search(re.escape(o) + r"(?![\w-])", found.group(1))]
    assert missing == [], f"docs/commands/{name}.md's synopsis omits {missing}"
