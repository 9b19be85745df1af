"""The console command exists and lists its subcommands."""

import subprocess
import sys
from pathlib import Path


def test_help_lists_subcommands():
    out = subprocess.run([sys.executable, "-m", "silbridge.tools", "--help"],
                         capture_output=True, text=True, check=True).stdout
    assert "silbridge" in out


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
