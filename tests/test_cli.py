"""The console command exists and lists its subcommands."""

import re
import subprocess
import sys
from pathlib import Path


# The commands the README and docs/ teach; each must be listed with its one-line summary.
DOCUMENTED = ("bridge", "fc", "fly", "sitl", "bench", "ablate", "transport", "analyze",
              "params", "shm-bench", "fc-bench", "clean", "tune", "soak", "speed")


def test_help_lists_subcommands():
    out = subprocess.run([sys.executable, "-m", "silbridge.tools", "--help"],
                         capture_output=True, text=True, check=True).stdout
    assert out.startswith("usage: silbridge ")
    listed = {}      # name -> summary, from argparse's "    name    summary" lines
    lines = out.splitlines()
    for i, line in enumerate(lines):
        m = re.match(r"^    (\S+)(?:\s{2,}(\S.*))?$", line)
        if m and not m.group(1).startswith("-"):
            summary = m.group(2) or (lines[i + 1].strip() if i + 1 < len(lines) else "")
            listed[m.group(1)] = summary
    for name in DOCUMENTED:
        assert name in listed, f"{name} missing from --help:\n{out}"
        assert len(listed[name]) > 10, f"{name} has no summary line"


def test_unknown_subcommand_is_refused():
    proc = subprocess.run([sys.executable, "-m", "silbridge.tools", "no-such-command"],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "invalid choice" in proc.stderr


def test_feature_off_takes_the_documented_names():
    """`--feature-off` accepts exactly the names docs/params.md documents (fc_sil/params.py)."""
    from silbridge.fc_sil.params import FEATURES
    doc = (Path(__file__).resolve().parents[1] / "docs" / "params.md").read_text()
    for name in FEATURES:
        assert f"`{name}`" in doc
    ok = subprocess.run([sys.executable, "-m", "silbridge.tools", "fly", "--processes", "1",
                         "--duration", "0.5", "--feature-off", "d_filter", "--json"],
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0, ok.stderr
    bad = subprocess.run([sys.executable, "-m", "silbridge.tools", "fly", "--feature-off",
                          "dfilter"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "d_filter" in bad.stderr
