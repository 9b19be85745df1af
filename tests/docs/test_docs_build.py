"""The docs site builds with `mkdocs build --strict`: a broken link, a page missing from the
nav's files or a bad anchor fails the suite, and the generated pages are part of the site."""

from __future__ import annotations

from pathlib import Path


def _page(site: Path, name: str) -> Path | None:
    """A page of the built site, whether mkdocs writes name/index.html or name.html."""
    for candidate in (site / name / "index.html", site / f"{name}.html"):
        if candidate.exists():
            return candidate
    return None


def test_site_builds_strictly(docs_site):
    assert docs_site.returncode == 0, f"mkdocs build --strict failed:\n{docs_site.output[-4000:]}"
    assert (docs_site.site / "index.html").exists()


def test_generated_pages_are_in_the_site(docs_site):
    assert docs_site.returncode == 0, docs_site.output[-4000:]
    cli = _page(docs_site.site, "reference/cli")
    assert cli is not None, "docs/reference/cli.md is not in the built site"
    html = cli.read_text()
    for command in ("silbridge fly", "silbridge bench", "silbridge transport"):
        assert command in html, f"{command} missing from the CLI reference page"
    results = _page(docs_site.site, "results")
    assert results is not None, ("docs/results.md is not in the built site: write it with "
                                 "`python -m silbridge.tools.docs.results_page --run "
                                 "--bench-out bench-out`")
    assert "The machine" in results.read_text()
