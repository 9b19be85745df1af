"""The MISSION_* protocol: upload, download, clear, set current (mission, fence, rally).

Upload: MISSION_COUNT -> we ask MISSION_REQUEST_INT(seq) for each item -> MISSION_ITEM_INT
(or the float MISSION_ITEM) -> MISSION_ACK. Every item is checked as it arrives; the first bad
one ends the upload with its precise MAV_MISSION_* code. A request is repeated after
``item_resend_s`` without an answer, and an upload with no progress for ``upload_timeout_s``
is cancelled (MAV_MISSION_OPERATION_CANCELLED). Only a complete, valid upload replaces the
stored mission; anything else leaves the previous one untouched.

Download: MISSION_REQUEST_LIST -> MISSION_COUNT -> the GCS asks for each item, answered in the
form asked for (_INT or float). As ArduCopter does, item 0 comes back as the current home and
RTL items with frame 0 and zero coordinates. A download while an upload is running is DENIED.
Fence (1) and rally (2) lists travel the same way when ``geo_stores`` holds their stores
(geo_store.py: no home slot, their own item rules, the same whole-or-nothing replacement);
a type without a store is answered MAV_MISSION_UNSUPPORTED. MISSION_CLEAR_ALL with
MAV_MISSION_TYPE_ALL clears all three.

``tx`` is the server's output side: send(link, msg), broadcast(msg), statustext(sev, text).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.geo_store import GeoStore
from silbridge.mavlink.gcs.mission_store import GLOBAL_FRAMES, MissionStore, check_item
from silbridge.mavlink.gcs.vehicle_api import MissionItem


@dataclass(slots=True)
class _Upload:
    link: object
    partner: tuple[int, int]
    count: int
    mission_type: int
    items: list[MissionItem] = field(default_factory=list)
    last_progress_s: float = 0.0
    last_request_s: float = 0.0


class MissionProtocol:
    def __init__(self, store: MissionStore, tx, sysid: int, compid: int, *,
                 on_updated: Callable[[tuple[MissionItem, ...]], None],
                 on_set_current: Callable[[object, object, int], None],
                 home_item: Callable[[], MissionItem | None],
                 item_resend_s: float = 1.0, upload_timeout_s: float = 8.0,
                 geo_stores: dict[int, GeoStore] | None = None,
                 on_geo_updated: Callable[[int, tuple[MissionItem, ...]], None] | None = None):
        self.store = store
        self.geo_stores = dict(geo_stores or {})
        self.on_geo_updated = on_geo_updated
        self.tx = tx
        self.sysid = sysid
        self.compid = compid
        self.on_updated = on_updated
        self.on_set_current = on_set_current
        self.home_item = home_item
        self.item_resend_s = item_resend_s
        self.upload_timeout_s = upload_timeout_s
        self._upload: _Upload | None = None
        self.uploads_ok = 0
        self.uploads_failed = 0

    @property
    def uploading(self) -> bool:
        return self._upload is not None

    # -- helpers ----------------------------------------------------------------------------------
    def _ack(self, link, partner: tuple[int, int], result: int, mission_type: int) -> None:
        self.tx.send(link, mav.MAVLink_mission_ack_message(partner[0], partner[1], result,
                                                           mission_type))

    def _request(self, up: _Upload, seq: int, now_s: float) -> None:
        self.tx.send(up.link, mav.MAVLink_mission_request_int_message(
            up.partner[0], up.partner[1], seq, up.mission_type))
        up.last_request_s = now_s

    def _store(self, mission_type: int):
        """The store of a mission type, or None when that type is not served."""
        if mission_type == mav.MAV_MISSION_TYPE_MISSION:
            return self.store
        return self.geo_stores.get(mission_type)

    @staticmethod
    def _what(mission_type: int) -> str:
        return {mav.MAV_MISSION_TYPE_FENCE: "Fence",
                mav.MAV_MISSION_TYPE_RALLY: "Rally"}.get(mission_type, "Mission")

    def _updated(self, mission_type: int) -> None:
        if mission_type == mav.MAV_MISSION_TYPE_MISSION:
            self.on_updated(self.store.items())
        elif self.on_geo_updated is not None:
            self.on_geo_updated(mission_type, self.geo_stores[mission_type].items())

    def _fail(self, result: int, reason: str | None = None) -> None:
        up = self._upload
        self._upload = None
        if up is None:
            return
        self.uploads_failed += 1
        self._ack(up.link, up.partner, result, up.mission_type)
        if reason:
            self.tx.statustext(mav.MAV_SEVERITY_WARNING, reason)

    @staticmethod
    def _partner(msg) -> tuple[int, int]:
        return msg.get_srcSystem(), msg.get_srcComponent()

    def _for_us(self, msg) -> bool:
        return (msg.target_system in (0, self.sysid)
                and msg.target_component in (0, self.compid, mav.MAV_COMP_ID_ALL))

    # -- dispatch ---------------------------------------------------------------------------------
    def handle(self, link, msg, now_s: float) -> None:
        if not self._for_us(msg):
            return
        t = msg.get_type()
        if t == "MISSION_COUNT":
            self._count(link, msg, now_s)
        elif t in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            self._item(link, msg, now_s, t == "MISSION_ITEM_INT")
        elif t == "MISSION_REQUEST_LIST":
            self._request_list(link, msg)
        elif t in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            self._send_item(link, msg, t == "MISSION_REQUEST_INT")
        elif t == "MISSION_CLEAR_ALL":
            self._clear(link, msg)
        elif t == "MISSION_SET_CURRENT":
            self.on_set_current(link, msg, msg.seq)
        elif t == "MISSION_ACK":
            up = self._upload
            if up is not None and self._partner(msg) == up.partner and up.link is link:
                # the GCS gave up on its own upload
                self._upload = None
                self.uploads_failed += 1

    # -- upload -----------------------------------------------------------------------------------
    def _count(self, link, msg, now_s: float) -> None:
        partner = self._partner(msg)
        mtype = msg.mission_type
        store = self._store(mtype)
        if store is None:
            self._ack(link, partner, mav.MAV_MISSION_UNSUPPORTED, mtype)
            return
        up = self._upload
        if up is not None and (up.partner != partner or up.link is not link):
            self._ack(link, partner, mav.MAV_MISSION_DENIED, mtype)   # someone else uploading
            return
        self._upload = None
        if msg.count > store.capacity:
            self.uploads_failed += 1
            self._ack(link, partner, mav.MAV_MISSION_NO_SPACE, mtype)
            self.tx.statustext(mav.MAV_SEVERITY_WARNING,
                               f"{self._what(mtype)} upload refused: {msg.count} items, room "
                               f"for {store.capacity}")
            return
        if msg.count == 0:
            store.clear()
            self.uploads_ok += 1
            self._ack(link, partner, mav.MAV_MISSION_ACCEPTED, mtype)
            self._updated(mtype)
            return
        self._upload = _Upload(link, partner, msg.count, mtype, last_progress_s=now_s)
        self._request(self._upload, 0, now_s)

    def _item(self, link, msg, now_s: float, is_int: bool) -> None:
        up = self._upload
        if up is None or up.partner != self._partner(msg) or up.link is not link:
            return      # not part of an upload in progress: ignore, as ArduPilot does
        what = self._what(up.mission_type)
        if msg.mission_type != up.mission_type:
            self._fail(mav.MAV_MISSION_INVALID,
                       f"{what} upload failed: item {msg.seq} of type {msg.mission_type}")
            return
        expected = len(up.items)
        if msg.seq >= up.count:
            self._fail(mav.MAV_MISSION_INVALID_SEQUENCE,
                       f"{what} upload failed: item {msg.seq} beyond count {up.count}")
            return
        if msg.seq < expected:
            return      # a repeat of an item we already have
        if msg.seq > expected:
            self._request(up, expected, now_s)
            return
        item, result = _to_item(msg, is_int)
        store = self._store(up.mission_type)
        if result == mav.MAV_MISSION_ACCEPTED:
            result = (check_item(item) if store is self.store
                      else store.check_item(item, up.items))
        if result != mav.MAV_MISSION_ACCEPTED:
            self._fail(result, f"{what} upload failed: item {msg.seq} (command "
                               f"{msg.command}, frame {msg.frame}): "
                               f"{mav.enums['MAV_MISSION_RESULT'][result].name}")
            return
        up.items.append(item)
        up.last_progress_s = now_s
        if len(up.items) < up.count:
            self._request(up, len(up.items), now_s)
            return
        self._upload = None
        result = store.replace(up.items)
        self._ack(up.link, up.partner, result, up.mission_type)
        if result == mav.MAV_MISSION_ACCEPTED:
            self.uploads_ok += 1
            self._updated(up.mission_type)
        else:
            self.uploads_failed += 1
            self.tx.statustext(mav.MAV_SEVERITY_WARNING, f"{what} upload failed: "
                               f"{mav.enums['MAV_MISSION_RESULT'][result].name}")

    def poll(self, now_s: float) -> float | None:
        """Resend a lost request / cancel a stalled upload; return the next deadline."""
        up = self._upload
        if up is None:
            return None
        if now_s - up.last_progress_s >= self.upload_timeout_s:
            self._fail(mav.MAV_MISSION_OPERATION_CANCELLED,
                       f"{self._what(up.mission_type)} upload timed out at item {len(up.items)} of {up.count}")
            return None
        if now_s - up.last_request_s >= self.item_resend_s:
            self._request(up, len(up.items), now_s)
        return min(up.last_request_s + self.item_resend_s,
                   up.last_progress_s + self.upload_timeout_s)

    # -- download ---------------------------------------------------------------------------------
    def _refused(self, link, partner, msg, all_ok: bool = False) -> bool:
        """ACK and refuse a download or clear of a type not served, or during an upload."""
        if self._store(msg.mission_type) is None and not (
                all_ok and msg.mission_type == mav.MAV_MISSION_TYPE_ALL):
            self._ack(link, partner, mav.MAV_MISSION_UNSUPPORTED, msg.mission_type)
            return True
        if self._upload is not None:
            self._ack(link, partner, mav.MAV_MISSION_DENIED, msg.mission_type)
            return True
        return False

    def _request_list(self, link, msg) -> None:
        partner = self._partner(msg)
        if self._refused(link, partner, msg):
            return
        self.tx.send(link, mav.MAVLink_mission_count_message(
            partner[0], partner[1], self._store(msg.mission_type).count(), msg.mission_type))

    def download_item(self, seq: int, mission_type: int = mav.MAV_MISSION_TYPE_MISSION
                      ) -> MissionItem | None:
        if mission_type != mav.MAV_MISSION_TYPE_MISSION:
            geo = self._store(mission_type).items()
            return geo[seq] if 0 <= seq < len(geo) else None
        items = self.store.items()
        if not 0 <= seq < len(items):
            return None
        item = items[seq]
        if seq == 0:
            home = self.home_item()
            if home is not None:
                item = home
        elif item.command == mav.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            item = dataclasses.replace(item, frame=mav.MAV_FRAME_GLOBAL, x=0, y=0, z=0.0)
        return dataclasses.replace(item, current=0)

    def _send_item(self, link, msg, as_int: bool) -> None:
        partner = self._partner(msg)
        if self._refused(link, partner, msg):
            return
        it = self.download_item(msg.seq, msg.mission_type)
        if it is None:
            self._ack(link, partner, mav.MAV_MISSION_INVALID_SEQUENCE, msg.mission_type)
            return
        if as_int:
            out = mav.MAVLink_mission_item_int_message(
                partner[0], partner[1], it.seq, it.frame, it.command, it.current,
                it.autocontinue, it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z,
                it.mission_type)
        else:
            scale = 1e-7 if it.frame in GLOBAL_FRAMES else 1.0
            out = mav.MAVLink_mission_item_message(
                partner[0], partner[1], it.seq, it.frame, it.command, it.current,
                it.autocontinue, it.param1, it.param2, it.param3, it.param4, it.x * scale,
                it.y * scale, it.z, it.mission_type)
        self.tx.send(link, out)

    # -- clear ------------------------------------------------------------------------------------
    def _clear(self, link, msg) -> None:
        partner = self._partner(msg)
        if self._refused(link, partner, msg, all_ok=True):
            return
        types = ([mav.MAV_MISSION_TYPE_MISSION, *self.geo_stores]
                 if msg.mission_type == mav.MAV_MISSION_TYPE_ALL else [msg.mission_type])
        for t in types:
            self._store(t).clear()
        self._ack(link, partner, mav.MAV_MISSION_ACCEPTED, msg.mission_type)
        for t in types:
            self._updated(t)


def _to_item(msg, is_int: bool) -> tuple[MissionItem, int]:
    """Convert MISSION_ITEM(_INT) to a MissionItem; float coordinates become degrees*1e7."""
    if is_int:
        x, y = int(msg.x), int(msg.y)
    else:
        scale = 1e7 if msg.frame in GLOBAL_FRAMES else 1.0
        if not math.isfinite(msg.x):
            return _blank(msg), mav.MAV_MISSION_INVALID_PARAM5_X
        if not math.isfinite(msg.y):
            return _blank(msg), mav.MAV_MISSION_INVALID_PARAM6_Y
        x, y = int(round(msg.x * scale)), int(round(msg.y * scale))
    return MissionItem(seq=msg.seq, frame=msg.frame, command=msg.command, current=msg.current,
                       autocontinue=msg.autocontinue, param1=msg.param1, param2=msg.param2,
                       param3=msg.param3, param4=msg.param4, x=x, y=y, z=msg.z,
                       mission_type=msg.mission_type), mav.MAV_MISSION_ACCEPTED


def _blank(msg) -> MissionItem:
    return MissionItem(seq=msg.seq, frame=msg.frame, command=msg.command)
