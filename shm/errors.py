"""Errors of the shared-memory transport, each saying what to do next.

Every class is user facing (``user_facing = True``): the `silbridge` command
prints the message on one line and exits with status 2. The C extension
reports segment failures as a status code plus a few facts (errno, pid,
what it found); :func:`from_status` turns them into the right exception.
The codes mirror ``enum sb_seg_status`` in shm/include/sb_segment.h
(tests/shm/test_errors.py checks they agree with the extension).
"""

from __future__ import annotations

import errno as _errno
import os

E_NAME = 1
E_CONFIG = 2
E_MISSING = 3
E_CREATING = 4
E_BUSY = 5
E_STALE = 6
E_PERM = 7
E_MAGIC = 8
E_VERSION = 9
E_LAYOUT = 10
E_PEER_BUSY = 11
E_OS = 12

SHM_DIR = "/dev/shm"
SHM_PREFIX = "silbridge-"


def shm_path(name: str) -> str:
    """Where the segment of instance `name` shows up in the file system (Linux)."""
    return os.path.join(SHM_DIR, SHM_PREFIX + name)


class ShmError(Exception):
    """Base class of every shared-memory transport error."""

    user_facing = True

    def __init__(self, message: str, *, name: str | None = None, pid: int = 0):
        super().__init__(message)
        self.name = name
        self.pid = pid


class SegmentNameError(ShmError, ValueError):
    """Instance name unusable as a shared-memory object name."""


class SegmentConfigError(ShmError, ValueError):
    """Slot counts out of range or not powers of two."""


class SegmentMissingError(ShmError, FileNotFoundError):
    """No segment with that instance name (the bridge is not running)."""


class SegmentBusyError(ShmError):
    """A live owner already holds that instance name."""


class StaleSegmentError(ShmError):
    """The segment's owner is gone: it crashed or closed without unlinking."""


class OwnerDeadError(StaleSegmentError):
    """Raised on attach when the bridge that created the segment is gone."""


class PermissionDeniedError(ShmError, PermissionError):
    """The segment belongs to another user (segments are mode 0600)."""


class LayoutMismatchError(ShmError):
    """Magic, format version or struct layout differ between the two sides."""


class PeerBusyError(ShmError):
    """Another live FC process is already attached to the segment."""


class SegmentClosedError(ShmError):
    """An operation on a segment (or ring) that was closed."""


class RingRoleError(ShmError):
    """Pushing on a ring this process consumes, or popping one it produces."""


class RecordKindError(ShmError, ValueError):
    """A pushed record's kind is not one of silbridge.shm.records.Kind."""


class AttachTimeoutError(SegmentMissingError, TimeoutError):
    """The segment did not appear (or finish being created) in time."""


def _what(info: dict) -> str:
    err = info.get("errno") or 0
    what = info.get("what") or "system call"
    return f"{what}: {os.strerror(err)}" if err else what


def from_status(code: int, name: str, info: dict) -> ShmError:
    """The exception for a segment status code from the C extension."""
    path = shm_path(name) if isinstance(name, str) else "?"
    pid = int(info.get("pid") or 0)
    if code == E_NAME:
        return SegmentNameError(
            f"instance name {name!r} is not usable: use 1-64 characters from "
            "A-Z a-z 0-9 _ - . (not starting with '.')", name=name)
    if code == E_CONFIG:
        return SegmentConfigError(
            "ring sizes must be powers of two between 4 and 16777216 slots: "
            "pass e.g. sensor_slots=1 << 14", name=name)
    if code == E_MISSING:
        return SegmentMissingError(
            f"no shared-memory segment {name!r} ({path}): is the bridge running? "
            f"Start `silbridge bridge --instance {name}` first, or check the instance name",
            name=name)
    if code == E_CREATING:
        return AttachTimeoutError(
            f"segment {name!r} exists but was not finished by its creator in time: "
            "retry, or give Segment.attach a longer timeout_s", name=name)
    if code == E_BUSY:
        who = f" (pid {pid})" if pid else ""
        return SegmentBusyError(
            f"segment {name!r} is in use by a running bridge{who}: stop it, or pick "
            "another instance name", name=name, pid=pid)
    if code == E_STALE:
        who = f" (pid {pid})" if pid else ""
        return OwnerDeadError(
            f"segment {name!r} is stale: the bridge that created it{who} is gone. "
            f"Restart the bridge (Segment.create replaces stale segments unless "
            f"replace_stale=False), or remove it with silbridge.shm.remove_stale({name!r}) "
            f"or `rm {path}`", name=name, pid=pid)
    if code == E_PERM:
        return PermissionDeniedError(
            f"permission denied on segment {name!r} ({path}): it belongs to another user "
            f"(segments are mode 0600). Run both sides as the same user, or have its owner "
            f"remove {path}", name=name)
    if code == E_MAGIC:
        return LayoutMismatchError(
            f"{path} is not a silbridge segment (magic {info.get('found_magic', 0):#x}): "
            f"remove it, or use another instance name", name=name)
    if code == E_VERSION:
        return LayoutMismatchError(
            f"segment {name!r} has format version {info.get('found_version')}, this build "
            "expects another: rebuild both sides from the same source "
            "(pip install -e . or setup.py build_ext --inplace) and restart them", name=name)
    if code == E_LAYOUT:
        return LayoutMismatchError(
            f"segment {name!r} was created with a different record/segment layout "
            f"(hash {info.get('found_hash', 0):#x}): rebuild both sides from the same "
            "source and restart them", name=name)
    if code == E_PEER_BUSY:
        return PeerBusyError(
            f"another FC process (pid {pid}) is attached to segment {name!r}: stop it "
            "first; only one consumer may attach", name=name, pid=pid)
    if info.get("errno") == _errno.ENOSPC:
        return ShmError(f"no space left in {SHM_DIR} for segment {name!r}: free some "
                        "space or use smaller rings", name=name)
    return ShmError(f"segment {name!r}: {_what(info)}", name=name)
