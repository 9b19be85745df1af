"""docs/results.md as the command writes it from a real (tiny) bench run: every section is
there, and its numbers are the bench's JSON, the machine's and the references' own. Speeds
are never compared with a target, only with each other as the page states them."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from importlib import metadata

import pytest

from silbridge.tools.transport.transport_report import markdown as transport_markdown

PAGE = [sys.executable, "-m", "silbridge.tools.docs.results_page"]
SECTIONS = ("# Results", "## The machine", "## Table 1: the campaign", "## Table 2: transports",
            "## Speed beside its references")


def _write(bench_out, page, *more, env=None):
    done = subprocess.run(PAGE + ["--bench-out", str(bench_out), "--out", str(page), *more],
                          capture_output=True, text=True, timeout=600, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    return page.read_text()


def _speed_row(text: str, label_start: str) -> list[str]:
    row = next(line for line in text.splitlines() if line.startswith(f"| {label_start}"))
    return [c.strip() for c in row.strip("|").split("|")]


@pytest.fixture(scope="module")
def page(tiny_bench, tmp_path_factory):
    env = {k: v for k, v in os.environ.items() if k != "SILBRIDGE_ARDUCOPTER"}
    env["PATH"] = os.path.dirname(sys.executable)      # no `arducopter` found on PATH either
    return _write(tiny_bench, tmp_path_factory.mktemp("results") / "results.md", env=env)


def test_every_section_in_order(page):
    where = [page.index(s) for s in SECTIONS]
    assert where == sorted(where)


def test_the_machine_is_described(page):
    machine = page.split("## The machine", 1)[1].split("\n## ", 1)[0]
    rows = dict(re.findall(r"^\| ([^|]+?) \| ([^|]+?) \|$", machine, re.M))
    assert rows["logical cores"] == str(os.cpu_count())
    assert rows["JSBSim"] == metadata.version("jsbsim")
    assert rows["kernel"].startswith("Linux " + os.uname().release)
    assert rows["CPU"] != "unknown" and rows["memory (GiB)"] != "unknown"
    load = [float(x) for x in rows["load average when the command started (1, 5, 15 min)"]
            .split(", ")]
    assert len(load) == 3 and all(x >= 0 for x in load)


def test_table1_and_the_campaign_figures_are_the_bench_output(page, tiny_bench):
    table = json.loads((tiny_bench / "table1.json").read_text())
    assert (tiny_bench / "table1.md").read_text().strip() in page
    rms = table["scenarios"]["S1"]["att_rms_deg"]["mean"]
    assert re.search(rf"^\| RMS \(deg\) \| {rms:.3f} ± ", page, re.M)
    wall, sim = table["wall_s"], table["sim_s_total"]
    assert f"**Wall time {wall:.1f} s** for {sim:.0f} s simulated" in page
    assert f"**{sim / wall:.1f}x real time** overall" in page


def test_table2_is_the_transport_json(page, tiny_bench):
    report = json.loads((tiny_bench / "transport" / "transport.json").read_text())
    assert transport_markdown(report).strip() in page
    p50 = report["transports"]["shm"]["latency_us"]["p50"]
    assert f"| sensor->FC latency p50 (us) | | | {p50:,.1f} |" in page


def test_speeds_and_ratios_agree_with_each_other_and_the_bench(page, tiny_bench):
    table = json.loads((tiny_bench / "table1.json").read_text())
    jsb = _speed_row(page, "bare JSBSim")
    run = _speed_row(page, "a campaign run, our FC")
    whole = _speed_row(page, "the whole campaign")
    j = float(jsb[1])
    assert j > 0 and jsb[2] == "1.00"
    assert run[1] == f"{table['scenarios']['S1']['realtime_factor']['mean']:.1f}"
    assert whole[1] == f"{table['sim_s_total'] / table['wall_s']:.1f}"
    for row in (run, whole):                 # the printed ratio is the printed speeds' ratio
        # each printed speed is rounded to 0.05, the ratio to 0.005
        slack = 0.006 + 0.05 * (1 + float(row[2])) / j
        assert float(row[2]) == pytest.approx(float(row[1]) / j, abs=slack)
        assert row[3] == "n/a"               # no ArduCopter: no ratio to it
    assert "ArduCopter's own physics: not measured (no ArduCopter SITL binary" in page


def test_a_folder_without_a_bench_run_is_refused(tmp_path):
    done = subprocess.run(PAGE + ["--bench-out", str(tmp_path), "--out", str(tmp_path / "r.md")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "silbridge bench --out" in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "r.md").exists()


def test_run_flies_the_campaign_itself(tmp_path, tiny_bench_args):
    """--run: the campaign is run by the same command, after the machine is described."""
    out = tmp_path / "bench-out"
    text = _write(out, tmp_path / "results.md", "--run", "--no-transport",
                  "--bench-args", " ".join(tiny_bench_args))
    assert (out / "table1.json").exists()
    assert "just before it ran the campaign" in text
    assert "## Table 2: transports\n\nNot measured" in text


@pytest.mark.skipif(not os.environ.get("SILBRIDGE_ARDUCOPTER"),
                    reason="set SILBRIDGE_ARDUCOPTER to an arducopter SITL binary to measure "
                           "its own-physics reference (none on this machine)")
def test_arducopter_reference_and_its_ratios(tiny_bench, tmp_path):
    text = _write(tiny_bench, tmp_path / "results.md")
    ac = _speed_row(text, "ArduCopter SITL on its own physics")
    run = _speed_row(text, "a campaign run, our FC")
    a = float(ac[1])
    assert a > 0 and ac[3] == "1.00"
    slack = 0.006 + 0.05 * (1 + float(run[3])) / a
    assert float(run[3]) == pytest.approx(float(run[1]) / a, abs=slack)
