"""Suite-wide: the test run must leave /dev/shm as it found it.

Every segment records its owner's $SILBRIDGE_OWNER_TAG (shm/include/sb_segment.h). This
session sets a tag of its own before any test runs, so every segment made by this pytest
process or any process it starts (fly, bridge, fc, campaign workers...) carries it, while
segments of other runs on the same machine (other engineers' suites, live flights) do not.
After the whole suite, any segment still carrying our tag is a leak: the run fails with
the list, and the leftovers are removed so the next run starts clean.
"""

from __future__ import annotations

import os
import time
import uuid

import pytest

SESSION_TAG = f"pytest-{os.getpid()}-{uuid.uuid4().hex[:8]}"
os.environ["SILBRIDGE_OWNER_TAG"] = SESSION_TAG

# A run we stopped may still be unwinding (closing its log, unlinking) when the last test
# returns; its segment counts as leaked only if it is still there after this.
_SETTLE_S = 10.0


def _ours():
    from silbridge.shm.leftovers import list_segments
    return [s for s in list_segments() if s.tag == SESSION_TAG]


def pytest_sessionfinish(session, exitstatus):
    try:
        from silbridge.shm import leftovers
    except ImportError:        # the extension is not built: nothing could have leaked
        return
    end = time.monotonic() + _SETTLE_S
    leaked = _ours()
    while leaked and time.monotonic() < end:
        time.sleep(0.2)
        leaked = _ours()
    if not leaked:
        return
    lines = [f"  /dev/shm/silbridge-{s.name} (owner pid {s.owner_pid}, "
             f"{'still running' if s.alive else 'owner gone'})" for s in leaked]
    for s in leaked:
        if s.stale:
            leftovers.remove(s.name)
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    text = (f"the test suite leaked {len(leaked)} shared-memory segment(s) "
            f"(owner tag {SESSION_TAG}):\n" + "\n".join(lines))
    if reporter is not None:
        reporter.write_sep("=", "shared-memory leak", red=True)
        reporter.write_line(text)
    else:
        print(text)
    session.exitstatus = pytest.ExitCode.TESTS_FAILED
