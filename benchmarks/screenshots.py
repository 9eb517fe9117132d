"""Screenshots of analyze's, fleet's and sweep's HTML pages for the bundled samples, taken with
headless Chromium (Debian's ``chromium``) at a 1,400-px window; each page must fit it.

Run from the repository root: ``python benchmarks/screenshots.py [OUT_DIR]`` (default
``docs/screenshots``). Writes ``analyze.png``, ``fleet.png`` and ``sweep.png`` (full pages) and
prints each page's ``document.documentElement.scrollWidth``; exits 1 when a page is wider than
the window, 2 when no Chromium is installed.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.outputs.cdp import Browser, chromium_binary
from tests.outputs.page_shots import WINDOW, build_pages, measure


def main() -> int:
    """Build the pages, photograph them and check their width."""
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/screenshots")
    binary = chromium_binary()
    if binary is None:
        print("no chromium binary: install Debian's chromium", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    wide = []
    with tempfile.TemporaryDirectory() as work:
        pages = build_pages(Path(work))
        with Browser(binary, Path(work) / "profile", f"{WINDOW},1000") as browser:
            for name, page in pages.items():
                png = out / f"{name}.png"
                width = measure(browser, page, png)
                print(f"{name}: scrollWidth {width} px at a {WINDOW}-px window -> {png}")
                if width > WINDOW:
                    wide.append(name)
    if wide:
        print(f"wider than the window: {', '.join(wide)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
