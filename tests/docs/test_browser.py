"""The pages a user opens, opened in a real browser (headless Chromium, Debian's package):
the benchmark's HTML report and the docs site. Each page renders (a title, a DOM, text),
every image loads, and the console stays free of errors; a screenshot of the report's first
screen is kept. The checker itself is shown to catch each of those faults on a bad page."""

from __future__ import annotations

import functools
import http.server
import struct
import threading
from pathlib import Path

import pytest

pytest.importorskip("websockets", reason="the `websockets` package (test extras) drives "
                                         "Chromium's DevTools protocol")

from silbridge.tools.docs.page_check import VIEWPORT, Browser, find_chromium  # noqa: E402

pytestmark = pytest.mark.skipif(
    find_chromium() is None,
    reason="no Chromium: install Debian's `chromium` package (tools/install_sysdeps.sh does, "
           "as root with apt) to check the pages in a browser")

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def browser():
    with Browser() as b:
        yield b


@pytest.fixture(scope="module")
def site_url(docs_site):
    """The built site over HTTP on a free port, as a reader's browser gets it."""
    assert docs_site.returncode == 0, f"the site did not build:\n{docs_site.output[-3000:]}"

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    handler = functools.partial(Quiet, directory=str(docs_site.site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()


def _assert_clean(rep, *, min_text: int = 100) -> None:
    assert rep.title, f"{rep.url}: no title"
    assert rep.elements > 20 and rep.text_chars >= min_text, f"{rep.url}: nearly empty page"
    assert not rep.broken_images, f"{rep.url}: images not loaded: {rep.broken_images}"
    assert not rep.errors, f"{rep.url}: console errors:\n" + "\n".join(rep.errors)


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR", f"{path} is not a PNG"
    return struct.unpack(">II", data[16:24])


def test_report_renders_with_its_plots_and_a_screenshot_is_kept(browser, tiny_bench, request):
    rep = browser.check((tiny_bench / "report" / "index.html").as_uri())
    _assert_clean(rep)
    assert rep.title == "silbridge benchmark report"
    plots = sorted(p.name for p in (tiny_bench / "report").glob("*.png"))
    shown = sorted(Path(i["src"]).name for i in rep.images)
    assert plots and shown == plots, "the page does not show exactly the report's plots"
    shot = browser.screenshot(str(tiny_bench / "report_first_screen.png"))
    assert _png_size(Path(shot)) == VIEWPORT and Path(shot).stat().st_size > 10_000
    from PIL import Image      # matplotlib's own dependency, so always there with the plots
    with Image.open(shot) as img:
        lo, hi = img.convert("L").getextrema()
    assert hi - lo > 100, "the screenshot is blank"
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line(f"\nreport's first screen kept: {shot}")


def _site_pages(site: Path) -> list[str]:
    """Every page of the built site as a path under its root ('' is the home page); the
    home page, a tutorial and the CLI reference must be among them."""
    pages = sorted(p.parent.relative_to(site).as_posix().removeprefix(".") + "/"
                   for p in site.rglob("index.html"))
    pages = [p.removeprefix("/") for p in pages]
    assert "" in pages and "reference/cli/" in pages, pages
    assert any(p.startswith("tutorials/") and p != "tutorials/" for p in pages), (
        "the site has no tutorial page under tutorials/")
    return pages


def test_docs_pages_render_with_images_and_no_console_errors(browser, site_url, docs_site):
    problems = []
    for page in _site_pages(docs_site.site):
        rep = browser.check(site_url + page)
        try:
            _assert_clean(rep)
        except AssertionError as exc:
            problems.append(str(exc).split("\nassert")[0])
        if page == "reference/cli/":
            assert "silbridge bench" in browser.evaluate("document.body.innerText")
    assert not problems, "\n".join(problems)


def test_the_checker_sees_a_broken_image_a_console_error_and_an_exception(browser, tmp_path):
    bad = tmp_path / "bad.html"
    bad.write_text("<!doctype html><html><head><title>bad</title></head><body>"
                   + "<p>text</p>" * 30 + "<img src='missing.png'>"
                   "<script>console.error('boom from the page');"
                   "setTimeout(() => { throw new Error('thrown late'); }, 0);"
                   "throw new Error('thrown at load');</script></body></html>")
    rep = browser.check(bad.as_uri())
    assert rep.broken_images and rep.broken_images[0].endswith("missing.png")
    text = "\n".join(rep.errors)
    assert "boom from the page" in text and "thrown at load" in text and "thrown late" in text
    with pytest.raises(AssertionError):
        _assert_clean(rep)
