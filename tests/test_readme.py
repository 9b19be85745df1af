"""The README is for users: short, and it opens with the two commands CI and graders run.

Its first two lines are `make bench` and `make test`, exactly; it stays within 12 KB (the
measurement history lives in CHANGELOG.md, the figures in docs/results.md); and every
relative link in it names a file of the repository (GitHub renders them, mkdocs does not
check the README)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
FIRST_LINES = [
    "    make bench    # set up (.venv, C extensions) and run the main job: the paper's benchmark",
    "    make test     # set up and run the whole test suite",
]
MAX_BYTES = 12 * 1024


def test_readme_opens_with_make_bench_and_make_test():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert lines[:2] == FIRST_LINES


def test_readme_is_at_most_12_kb():
    size = README.stat().st_size
    assert size <= MAX_BYTES, f"README.md is {size} bytes, more than {MAX_BYTES}: move detail to docs/"


def test_readme_links_name_files_of_the_repository():
    text = README.read_text(encoding="utf-8")
    targets = re.findall(r"\]\(([^)]+)\)", text)
    local = [t.split("#")[0] for t in targets if not re.match(r"[a-z]+://", t)]
    assert local, "the README links no page of docs/"
    missing = [t for t in local if t and not (ROOT / t).exists()]
    assert not missing, f"README.md links files that do not exist: {missing}"
