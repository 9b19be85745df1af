"""Segments left behind: list them, tell live from stale, reclaim the stale ones.

Every segment is a file /dev/shm/silbridge-<instance>. Its owner unlinks it on
every exit path it controls (errors, failed start-up checks, a dead peer,
Ctrl-C); a SIGKILL, an OOM kill or a power cut leaves it behind. Such a
leftover is "stale": its owner's lock is gone (shm/include/sb_segment.h). It
holds no data anyone needs, only memory (tmpfs pages count as RAM).

- `list_segments()` reads each header without attaching (`_ring.probe`).
- `remove(name)` removes a segment only if it is stale (`_ring.remove_stale`
  re-checks the owner lock, so a live run is never touched).
- `reclaim_stale()` is what `Segment.create` runs at every start: it removes
  stale segments older than a minute that carry the same owner tag as this
  process ($SILBRIDGE_OWNER_TAG, usually empty), so a test that made a stale
  segment on purpose a moment ago, or another team's job, is left alone.

`silbridge clean` (tools/cli/cmd_clean.py) lists and removes them by hand.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import os
import time

from . import _ring
from .errors import SegmentBusyError, ShmError

SHM_DIR = "/dev/shm"
PREFIX = "silbridge-"
TAG_ENV = "SILBRIDGE_OWNER_TAG"
# reclaim_stale leaves younger stale segments alone (a crash being diagnosed, a test).
RECLAIM_MIN_AGE_S = 60.0


@dataclasses.dataclass
class SegmentInfo:
    name: str            # instance name (the file is /dev/shm/silbridge-<name>)
    owner_pid: int
    alive: bool          # its owner still holds it
    age_s: float | None  # since creation
    bytes: int
    tag: str             # the owner's $SILBRIDGE_OWNER_TAG
    version: int         # segment format version (0: never published)

    @property
    def stale(self) -> bool:
        return not self.alive


def own_tag() -> str:
    return os.environ.get(TAG_ENV, "")


def list_segments(pattern: str | None = None) -> list[SegmentInfo]:
    """Every silbridge segment on this machine (instance names matching the glob `pattern`)."""
    try:
        files = sorted(os.listdir(SHM_DIR))
    except OSError:
        return []
    now_ns = time.time_ns()
    out = []
    for f in files:
        if not f.startswith(PREFIX):
            continue
        name = f[len(PREFIX):]
        if pattern is not None and not fnmatch.fnmatchcase(name, pattern):
            continue
        try:
            p = _ring.probe(name)
        except ShmError:
            continue          # not ours to read (permission) or a name we would not make
        if p is None:
            continue          # gone since listdir
        age = (now_ns - p["created_unix_ns"]) / 1e9 if p["created_unix_ns"] else None
        out.append(SegmentInfo(name, p["owner_pid"], p["owner_alive"], age, p["bytes"],
                               p["tag"], p["version"]))
    return out


def remove(name: str) -> bool:
    """Remove segment `name` if stale; False if it was already gone or its owner lives."""
    try:
        return _ring.remove_stale(name)
    except SegmentBusyError:
        return False


def reclaim_stale(*, tag: str | None = None, min_age_s: float = RECLAIM_MIN_AGE_S) -> list[str]:
    """Remove stale segments with owner tag `tag` (default: ours) older than min_age_s."""
    tag = own_tag() if tag is None else tag
    removed = []
    for s in list_segments():
        if s.stale and s.tag == tag and s.age_s is not None and s.age_s >= min_age_s:
            if remove(s.name):
                removed.append(s.name)
    return removed
