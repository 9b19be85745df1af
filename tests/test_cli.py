"""The console command exists and lists its subcommands."""

import subprocess
import sys


def test_help_lists_subcommands():
    out = subprocess.run([sys.executable, "-m", "silbridge.tools", "--help"],
                         capture_output=True, text=True, check=True).stdout
    assert "silbridge" in out


def test_unknown_subcommand_is_refused():
    proc = subprocess.run([sys.executable, "-m", "silbridge.tools", "no-such-command"],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "invalid choice" in proc.stderr
