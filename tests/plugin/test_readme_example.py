"""The regression test of the recorded mission in docs/pytest.md, run exactly as shown there."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pytest

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[2]
FIRST_LINE = "# tests/test_nav2_mission.py"


def readme_example() -> str:
    """docs/pytest.md's Python code block that starts with ``# tests/test_nav2_mission.py``."""
    readme = (ROOT / "docs" / "pytest.md").read_text(encoding="utf-8")
    pattern = re.compile(r"^```python\n(.*?)^```$", flags=re.MULTILINE | re.DOTALL)
    found = [m.group(1) for m in pattern.finditer(readme) if m.group(1).startswith(FIRST_LINE)]
    assert len(found) == 1, f"docs/pytest.md: one python block starting with {FIRST_LINE!r}"
    return found[0]


def test_the_readme_regression_test_runs_as_shown(pytester: pytest.Pytester) -> None:
    # The layout of a repository: the test in tests/, the samples and rules beside it.
    for folder in ("sample_bags", "rules"):
        (pytester.path / folder).symlink_to(ROOT / folder, target_is_directory=True)
    tests = pytester.path / "tests"
    tests.mkdir()
    (tests / "test_nav2_mission.py").write_text(readme_example(), encoding="utf-8")
    golden = tests / "goldens" / "test_nav2_mission" / "test_the_whole_report_is_unchanged.json"

    # as docs/pytest.md says: once with --update-golden, then in CI without
    first = pytester.runpytest("tests", "--update-golden")
    first.assert_outcomes(passed=3)
    first.stdout.fnmatch_lines(["*medkit-replay golden reports written*", str(golden)])
    report = json.loads(golden.read_text(encoding="utf-8"))
    assert report["schema"] == "medkit-replay/report/v1"
    pytester.runpytest("tests").assert_outcomes(passed=3)

    # a run that differs from its golden (here: a fault the golden does not know) fails
    report["faults"] = [f for f in report["faults"] if f["fault_code"] != "MOTOR_LEFT_OVERHEAT"]
    golden.write_text(json.dumps(report), encoding="utf-8")
    result = pytester.runpytest("tests")
    result.assert_outcomes(passed=2, failed=1)
    result.stdout.fnmatch_lines(
        [
            "E       AssertionError: the run differs from its golden report",
            "E       reports differ: 1 difference (fault added: 1; time tolerance 0.000 s)",
            "E       MOTOR_LEFT_OVERHEAT",
            "E         + fault *absent *HEALED",
        ]
    )


def test_the_readme_failure_example_is_what_a_failure_shows(pytester: pytest.Pytester) -> None:
    """docs/pytest.md's sample failure output is the real one (for a window of 75 to 76 s)."""
    readme = (ROOT / "docs" / "pytest.md").read_text(encoding="utf-8")
    shown = re.search(
        r"^```\n(E +AssertionError: expected MOTOR_LEFT_OVERHEAT.*?)^```$",
        readme,
        flags=re.MULTILINE | re.DOTALL,
    )
    assert shown is not None
    for folder in ("sample_bags", "rules"):
        (pytester.path / folder).symlink_to(ROOT / folder, target_is_directory=True)
    tests = pytester.path / "tests"
    tests.mkdir()
    code = readme_example().replace("within=(75.0, 80.0)", "within=(75.0, 76.0)")
    (tests / "test_nav2_mission.py").write_text(code, encoding="utf-8")
    result = pytester.runpytest("tests", "-k", "overheat")
    result.assert_outcomes(failed=1, deselected=2)
    result.stdout.fnmatch_lines(shown.group(1).splitlines())
