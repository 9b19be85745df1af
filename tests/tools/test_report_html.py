"""The benchmark report page (tools/benchmark/report_html.py, tools/benchmark/report.py), parsed as HTML.

A small real campaign (JSBSim + SIL FC, two scenarios, two runs each) writes its report;
the page is parsed with the standard library's HTML parser: Table 1 is an HTML table
with the scenarios as column groups and the paper's figures beside ours, every plot is a
figure with an image that exists and a caption, the configuration is there, and the
links to the kept logs resolve. No raw Markdown table is left on the page.
"""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path

import pytest

from silbridge.tools.benchmark.campaign import make_specs, run_campaign
from silbridge.tools.benchmark.report import write_report
from silbridge.tools.benchmark.report_html import table1_html
from silbridge.tools.benchmark.table1 import PAPER, ROWS, aggregate, markdown

VOID = {"meta", "img", "br", "link", "input", "hr"}


class Node:
    def __init__(self, tag, attrs, parent=None):
        self.tag, self.attrs, self.parent = tag, dict(attrs), parent
        self.children: list[Node] = []
        self.text = ""

    def all(self, tag):
        for c in self.children:
            if c.tag == tag:
                yield c
            yield from c.all(tag)

    def full_text(self) -> str:
        return self.text + "".join(c.full_text() for c in self.children)


class Tree(HTMLParser):
    def __init__(self, text: str):
        super().__init__()
        self.root = self.cur = Node("#root", {})
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        node = Node(tag, attrs, self.cur)
        self.cur.children.append(node)
        if tag not in VOID:
            self.cur = node

    def handle_endtag(self, tag):
        n = self.cur
        while n is not self.root and n.tag != tag:
            n = n.parent
        assert n is not self.root, f"</{tag}> closes nothing"
        self.cur = n.parent

    def handle_data(self, data):
        self.cur.text += data


def _rows(table: Node) -> list[list[Node]]:
    return [list(c for c in tr.children if c.tag in ("td", "th")) for tr in table.all("tr")]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    specs = make_specs(["S1", "S3"], 2, 8.0, out, keep_logs="first",
                       windows=((0.0, 4.0), (4.0, 5.0), (5.0, 8.0), (6.0, 8.0)))
    results = run_campaign(specs, jobs=1)
    table = aggregate(results)
    table.update({"runs": 2, "duration_s": 8.0, "wall_s": 1.0, "fc": ["ours"],
                  "executor": "local", "params": {}, "sim_s_total": 32.0})
    index = write_report(results, markdown(table), table, out)
    return index, Tree(index.read_text()).root, results


def test_table1_is_an_html_table_with_the_papers_figures(report):
    _index, root, _results = report
    tables = [t for t in root.all("table") if t.attrs.get("class") == "table1"]
    assert len(tables) == 1
    rows = _rows(tables[0])
    groups = [c.full_text() for c in rows[0] if c.attrs.get("class") == "group"]
    assert groups == ["S1", "S3"]
    assert [c.full_text() for c in rows[1]] == ["ours", "paper", "ours", "paper"]
    body = rows[2:]
    assert len(body) == len(ROWS)
    assert all(len(r) == 5 for r in body)
    rms = next(r for r in body if r[0].full_text().startswith("RMS"))
    assert rms[2].full_text() == str(PAPER["S1"]["att_rms_deg"])
    assert rms[4].full_text() == str(PAPER["S3"]["att_rms_deg"])
    assert "±" in rms[1].full_text() and rms[1].attrs["title"] == "n = 2"
    # No Markdown table left inside a <pre>.
    assert not any("|---" in p.full_text() for p in root.all("pre"))


def test_plots_are_figures_with_captions_and_images_that_exist(report):
    index, root, _results = report
    figures = list(root.all("figure"))
    assert len(figures) >= 6            # 3 traces per scenario with a kept log, box plots
    for fig in figures:
        imgs = list(fig.all("img"))
        caps = list(fig.all("figcaption"))
        assert len(imgs) == 1 and len(caps) == 1
        assert (index.parent / imgs[0].attrs["src"]).is_file()
        assert len(caps[0].full_text()) > 30
    assert any("S3" in c.full_text() and "attitude" in c.full_text()
               for c in root.all("figcaption"))


def test_configuration_and_links_to_the_logs(report):
    index, root, results = report
    cfg = next(dl for dl in root.all("dl") if dl.attrs.get("class") == "cfg")
    terms = {dt.full_text(): dd.full_text() for dt, dd in
             zip(cfg.all("dt"), cfg.all("dd"))}
    assert terms["runs per scenario"] == "2" and terms["sim time per run"] == "8 s"
    assert "physics 1000 Hz" in terms["rates (from the first log)"]
    assert terms["seeds"] == "1..2"
    links = [a.attrs["href"] for a in root.all("a") if a.attrs["href"].endswith(".mcap")]
    kept = [r for r in results if Path(r.spec.log_path).exists()]
    assert len(links) == len(kept) == 2
    for href in links:
        assert (index.parent / href).resolve().is_file()
    runs = next(t for t in root.all("table") if t.attrs.get("class") == "runs")
    assert len(_rows(runs)) == 1 + len(results)
    assert all(r[6].full_text() == "ok" for r in _rows(runs)[1:])


def test_controllers_side_by_side_when_several_ran():
    stat = {"mean": 0.5, "std": 0.1, "n": 3}
    table = {"scenarios": {"S1": {"att_rms_deg": stat}, "S1 ArduCopter": {"att_rms_deg": stat},
                           "S2": {"att_rms_deg": stat}, "S2 ArduCopter": {}}}
    root = Tree(table1_html(table)).root
    rows = _rows(next(root.all("table")))
    assert [c.full_text() for c in rows[1]] == ["ours", "ArduCopter", "paper"] * 2
    assert [c.attrs.get("colspan") for c in rows[0][1:]] == ["3", "3"]
    rms = next(r for r in rows[2:] if r[0].full_text().startswith("RMS"))
    assert [c.full_text() for c in rms[1:]] == ["0.500 ± 0.100", "0.500 ± 0.100", "1.227",
                                                "0.500 ± 0.100", "n/a", "2.04"]


def test_vibration_section_has_spectrum_and_spectrogram_with_rotor_harmonics(report):
    """Per scenario with a kept log: a spectrum (analysis window) and a spectrogram (whole
    run) of gyro and accel, the rotor harmonics marked from the log's /rotor channel."""
    from silbridge.tools.logs.log_reader import read_log

    index, root, results = report
    h2 = [h for h in root.all("h2") if h.attrs.get("id") == "vibration"]
    assert len(h2) == 1
    caps = [c.full_text() for c in root.all("figcaption")]
    for r in results:
        if r.spec.run_index != 0:
            continue
        sc = r.spec.scenario
        spec = [c for c in caps if c.startswith(f"{sc}, ") and "amplitude spectrum" in c]
        gram = [c for c in caps if c.startswith(f"{sc}, ") and "spectrogram" in c]
        assert len(spec) == 1 and len(gram) == 1, caps
        rotor = read_log(r.spec.log_path).channels["/rotor"]
        assert len(rotor)
        assert "rotor harmonics 1x, 2x (blade pass), 3x at rotor" in spec[0]
        assert "1x, 2x (blade pass) and 3x the rotor frequency over time" in gram[0]
    for fig in root.all("figure"):
        img = next(fig.all("img")).attrs["src"]
        assert (index.parent / img).is_file()
    assert any("spectrogram" in next(f.all("img")).attrs["src"] for f in root.all("figure"))
