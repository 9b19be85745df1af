"""Every error case of the segment, each with a message that names the fix:
missing, busy, stale (owner dead), permission, magic/version/layout
mismatch, a second peer, bad names and sizes; plus mode 0600 and the safe
clean-up of stale segments."""

from __future__ import annotations

import os
import signal
import stat
import struct
import subprocess
import sys
import time

import pytest

from silbridge.shm import (
    AttachTimeoutError,
    LayoutMismatchError,
    OwnerDeadError,
    PeerBusyError,
    PermissionDeniedError,
    Segment,
    SegmentBusyError,
    SegmentConfigError,
    SegmentMissingError,
    SegmentNameError,
    ShmError,
    StaleSegmentError,
    remove_stale,
)
from silbridge.shm.errors import shm_path

# Byte offsets in the segment header (shm/include/sb_segment.h).
OFF_MAGIC, OFF_VERSION, OFF_HASH = 0, 8, 16


def _crashed_owner(name: str) -> int:
    """Create segment `name` in a child that is then killed; returns its pid."""
    code = ("import sys, os, signal\n"
            "from silbridge.shm import Segment\n"
            f"seg = Segment.create({name!r}, sensor_slots=64, actuator_slots=16)\n"
            "print(os.getpid(), flush=True)\n"
            "os.kill(os.getpid(), signal.SIGKILL)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    return int(proc.stdout.split()[0])


def _poke(name: str, offset: int, data: bytes) -> None:
    fd = os.open(shm_path(name), os.O_RDWR)
    try:
        os.pwrite(fd, data, offset)
    finally:
        os.close(fd)


def test_errors_are_user_facing():
    assert ShmError.user_facing
    for cls in (SegmentMissingError, OwnerDeadError, PermissionDeniedError,
                LayoutMismatchError, PeerBusyError, SegmentBusyError):
        assert issubclass(cls, ShmError)


def test_missing_segment_asks_whether_the_bridge_runs(name):
    with pytest.raises(SegmentMissingError, match="is the bridge running"):
        Segment.attach(name)
    t0 = time.monotonic()
    with pytest.raises(AttachTimeoutError, match=r"waited 0\.05 s"):
        Segment.attach(name, timeout_s=0.05)
    assert time.monotonic() - t0 >= 0.05


@pytest.mark.parametrize("stale_first", [False, True])
def test_attach_waits_for_the_bridge(name, stale_first):
    if stale_first:  # a crashed bridge left its segment; the restarted one replaces it
        _crashed_owner(name)
    code = ("import time\nfrom silbridge.shm import Segment\ntime.sleep(0.3)\n"
            f"seg = Segment.create({name!r}, sensor_slots=16, actuator_slots=16)\n"
            "time.sleep(3)\n")
    proc = subprocess.Popen([sys.executable, "-c", code])
    try:
        seg = Segment.attach(name, timeout_s=20.0)
        assert seg.peer_pid == proc.pid and seg.peer_alive()
        seg.close()
    finally:
        proc.kill()
        proc.wait()


def test_a_stale_segment_being_replaced_is_not_attached(name):
    """A bridge replacing a crashed bridge's segment holds the old segment's owner lock for a
    moment before it unlinks it: an FC attaching just then finds the lock held, but the
    owner in the header dead, and waits for the new segment instead of joining the dead one
    (CI once saw attach return the crashed owner's segment in that moment). The replacing
    bridge's moment is held open here by a process that locks the owner byte and waits."""
    dead = _crashed_owner(name)
    code = ("import fcntl, os, time\n"
            f"fd = os.open({shm_path(name)!r}, os.O_RDWR)\n"
            "fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB, 1, 0)\n"
            "print('locked', flush=True)\n"
            "time.sleep(30)\n")
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(OwnerDeadError, match=f"pid {dead}"):
            Segment.attach(name)
    finally:
        holder.kill()
        holder.wait()


def test_segment_is_private_to_its_user(name):
    with Segment.create(name, sensor_slots=16, actuator_slots=16):
        mode = stat.S_IMODE(os.stat(shm_path(name)).st_mode)
        assert mode == 0o600


def test_second_live_owner_is_refused_and_nothing_is_touched(name):
    with Segment.create(name, sensor_slots=16, actuator_slots=16) as first:
        first.set_word(0, 42)
        with pytest.raises(SegmentBusyError, match="running bridge"):
            Segment.create(name)  # replace_stale does not apply to a live owner
        with pytest.raises(SegmentBusyError):
            remove_stale(name)
        assert first.word(0) == 42 and os.path.exists(shm_path(name))


def test_dead_owner_is_detected_by_attach_and_replaced_by_create(name):
    pid = _crashed_owner(name)
    with pytest.raises(OwnerDeadError, match=f"pid {pid}.*Restart the bridge"):
        Segment.attach(name)
    with pytest.raises(StaleSegmentError, match="stale"):
        Segment.create(name, replace_stale=False)
    with Segment.create(name, sensor_slots=16, actuator_slots=16) as seg:  # replaces it
        assert seg.info["owner_pid"] == os.getpid()
        peer = Segment.attach(name)
        assert peer.peer_pid == os.getpid()
        peer.close()


def test_remove_stale_removes_only_dead_segments(name):
    assert remove_stale(name) is False  # nothing there
    _crashed_owner(name)
    assert remove_stale(name) is True
    assert not os.path.exists(shm_path(name))


def test_owner_closed_without_unlink_counts_as_gone(name):
    seg = Segment.create(name, sensor_slots=16, actuator_slots=16)
    seg.close()  # no unlink
    with pytest.raises(OwnerDeadError):
        Segment.attach(name)
    Segment.create(name, sensor_slots=16, actuator_slots=16).close()


def test_foreign_object_is_not_taken_for_a_segment(name):
    with open(shm_path(name), "wb") as f:
        f.write(b"not a silbridge segment".ljust(8192, b"\0"))
    with pytest.raises(LayoutMismatchError, match="not a silbridge segment"):
        Segment.attach(name)


@pytest.mark.parametrize("offset, value, pattern", [
    (OFF_VERSION, struct.pack("<I", 99), "format version 99.*rebuild both sides"),
    (OFF_HASH, struct.pack("<Q", 12345), "different record/segment layout.*rebuild both sides"),
])
def test_version_and_layout_mismatch_say_rebuild(name, offset, value, pattern):
    with Segment.create(name, sensor_slots=16, actuator_slots=16):
        _poke(name, offset, value)
        with pytest.raises(LayoutMismatchError, match=pattern):
            Segment.attach(name)


def test_second_peer_is_refused_while_the_first_lives(name):
    with Segment.create(name, sensor_slots=16, actuator_slots=16):
        first = Segment.attach(name)
        with pytest.raises(PeerBusyError, match=f"pid {os.getpid()}"):
            Segment.attach(name)
        first.close()
        Segment.attach(name).close()  # a closed peer frees the slot


def _attach_as_nobody(name: str) -> str:
    """Root ignores file modes: attach from a forked child that dropped to
    user nobody (the module is already imported, nothing is exec'd)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # child: never returns into pytest
        msg = "no error"
        try:
            os.setgid(65534)
            os.setuid(65534)
            Segment.attach(name)
        except PermissionDeniedError as exc:
            msg = str(exc)
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            msg = f"{type(exc).__name__}: {exc}"
        os.write(w, msg.encode())
        os._exit(0)
    os.close(w)
    with os.fdopen(r) as f:
        msg = f.read()
    os.waitpid(pid, 0)
    return msg


def test_permission_denied_names_the_fix(name):
    with Segment.create(name, sensor_slots=16, actuator_slots=16):
        if os.geteuid() == 0:
            msg = _attach_as_nobody(name)
            assert "permission denied" in msg and "same user" in msg, msg
        else:
            os.chmod(shm_path(name), 0)
            with pytest.raises(PermissionDeniedError, match="same user"):
                Segment.attach(name)


@pytest.mark.parametrize("bad", ["", "a/b", "x" * 65, ".hidden", "sp ace"])
def test_bad_instance_names(bad):
    with pytest.raises(SegmentNameError, match="A-Z a-z 0-9"):
        Segment.create(bad)


@pytest.mark.parametrize("slots", [0, 3, 100, 1 << 25])
def test_ring_sizes_must_be_powers_of_two(name, slots):
    with pytest.raises(SegmentConfigError, match="powers of two"):
        Segment.create(name, sensor_slots=slots)


def test_closed_segment_refuses_work(name):
    seg = Segment.create(name, sensor_slots=16, actuator_slots=16)
    ring = seg.sensors
    seg.unlink()
    seg.close()
    seg.close()  # idempotent
    from silbridge.shm import SegmentClosedError
    with pytest.raises(SegmentClosedError, match="closed"):
        ring.try_push(b"\x01" + b"\0" * 63)
    with pytest.raises(SegmentClosedError):
        seg.word(0)
    assert not os.path.exists(shm_path(name))
