"""`silbridge clean` and the start-up reclaim of stale segments (shm/leftovers.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import uuid

from silbridge.shm import Segment
from silbridge.shm.leftovers import list_segments, reclaim_stale, remove

SB = [sys.executable, "-m", "silbridge.tools"]
_CRASH = "import os, sys; from silbridge.shm import Segment; Segment.create(sys.argv[1]); " \
         "os._exit(9)"


def crashed_segment(name: str, tag: str | None = None) -> None:
    """A segment whose owner died without unlinking it (as after a SIGKILL)."""
    env = dict(os.environ)
    if tag is not None:
        env["SILBRIDGE_OWNER_TAG"] = tag
    subprocess.run([sys.executable, "-c", _CRASH, name], env=env, check=False, timeout=60)
    assert os.path.exists(f"/dev/shm/silbridge-{name}")


def clean(*args) -> dict:
    r = subprocess.run(SB + ["clean", "--json", *args], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_clean_lists_then_removes_stale_and_leaves_live_alone():
    base = f"cln-{os.getpid()}-{uuid.uuid4().hex[:6]}"
    stale, live = f"{base}-dead", f"{base}-live"
    crashed_segment(stale)
    with Segment.create(live):
        listed = clean("--dry-run", "--match", f"{base}-*")
        states = {s["name"]: s["state"] for s in listed["segments"]}
        assert states == {stale: "stale", live: "live"}
        assert os.path.exists(f"/dev/shm/silbridge-{stale}")      # dry run: nothing removed
        done = clean("--match", f"{base}-*")
        assert done["removed"] == [stale]
        assert not os.path.exists(f"/dev/shm/silbridge-{stale}")
        assert os.path.exists(f"/dev/shm/silbridge-{live}")
    text = subprocess.run(SB + ["clean", "--list", "--match", f"{base}-*"], capture_output=True,
                          text=True, timeout=60).stdout
    assert "no silbridge segments" in text


def test_reclaim_at_start_takes_only_our_own_leftovers():
    base = f"rcl-{os.getpid()}-{uuid.uuid4().hex[:6]}"
    ours, theirs = f"{base}-ours", f"{base}-theirs"
    crashed_segment(ours)
    crashed_segment(theirs, tag=f"someone-else-{uuid.uuid4().hex[:6]}")
    try:
        # Young leftovers stay (a crash being looked at); older ones of our tag go.
        assert ours not in reclaim_stale()
        removed = reclaim_stale(min_age_s=0.0)
        assert ours in removed and theirs not in removed
        names = {s.name for s in list_segments(f"{base}-*")}
        assert names == {theirs}
    finally:
        remove(theirs)
        remove(ours)
