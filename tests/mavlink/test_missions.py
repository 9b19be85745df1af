"""MISSION_* protocol: upload, download, clear, set current, failures keep the old mission,
item-reached and MISSION_CURRENT, QGC WPL round trip through the server."""

from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from mavtest_client import wait_until

from silbridge.mavlink.gcs.vehicle_api import CopterMode, MissionItem
from silbridge.mavlink.gcs.wpl import load_wpl, save_wpl

G = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def mission(n_wp: int = 3) -> list[MissionItem]:
    items = [MissionItem(0, mav.MAV_FRAME_GLOBAL, mav.MAV_CMD_NAV_WAYPOINT, 0, 1,
                         0, 0, 0, 0, -353632621, 1491652374, 584.0)]
    items.append(MissionItem(1, G, mav.MAV_CMD_NAV_TAKEOFF, 1, 1, 0, 0, 0, float("nan"),
                             0, 0, 10.0))
    items.append(MissionItem(2, mav.MAV_FRAME_MISSION, mav.MAV_CMD_DO_CHANGE_SPEED, 0, 1,
                             1, 6.0, -1, 0, 0, 0, 0.0))
    for k in range(n_wp):
        items.append(MissionItem(len(items), G, mav.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 2.0, 0,
                                 float("nan"), -353632621 + 1000 * (k + 1), 1491652374,
                                 20.0 + k))
    items.append(MissionItem(len(items), G, mav.MAV_CMD_NAV_LOITER_TIME, 0, 1, 5.0, 0, 0, 0,
                             -353632621, 1491652374, 20.0))
    items.append(MissionItem(len(items), G, mav.MAV_CMD_NAV_LAND, 0, 1, 0, 0, 0, 0, 0, 0, 0.0))
    items.append(MissionItem(len(items), mav.MAV_FRAME_MISSION,
                             mav.MAV_CMD_NAV_RETURN_TO_LAUNCH, 0, 1))
    return items


def item_msg(it: MissionItem, seq=None):
    return mav.MAVLink_mission_item_int_message(
        1, 1, it.seq if seq is None else seq, it.frame, it.command, it.current,
        it.autocontinue, it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z,
        it.mission_type)


def upload(client, items, *, count=None, stop_after=None, replace=None, timeout_s=2.0):
    """Answer the server's requests; return the final MISSION_ACK (or None)."""
    client.drain()
    client.send(mav.MAVLink_mission_count_message(1, 1, len(items) if count is None else count,
                                                  0))
    sent = 0
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for m in client.pump(0.05):
            t = m.get_type()
            if t == "MISSION_ACK":
                return m
            if t == "MISSION_REQUEST_INT":
                if stop_after is not None and sent >= stop_after:
                    continue
                it = items[m.seq]
                if replace and m.seq in replace:
                    it = replace[m.seq]
                client.send(item_msg(it))
                sent += 1
    return None


def download(client, as_int=True, timeout_s=2.0):
    client.drain()
    client.send(mav.MAVLink_mission_request_list_message(1, 1, 0))
    cnt = client.wait("MISSION_COUNT", timeout_s=timeout_s)
    assert cnt is not None and (cnt.target_system, cnt.target_component) == (255, 190)
    out = []
    for seq in range(cnt.count):
        if as_int:
            client.send(mav.MAVLink_mission_request_int_message(1, 1, seq, 0))
            m = client.wait("MISSION_ITEM_INT", lambda m: m.seq == seq, timeout_s)
        else:
            client.send(mav.MAVLink_mission_request_message(1, 1, seq, 0))
            m = client.wait("MISSION_ITEM", lambda m: m.seq == seq, timeout_s)
        assert m is not None
        out.append(m)
    client.send(mav.MAVLink_mission_ack_message(1, 1, 0, 0))
    return out


def same(a, b) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a)
                      and math.isnan(b))


def test_upload_download_roundtrip(env):
    items = mission()
    ack = upload(env.client, items)
    assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED
    assert (ack.target_system, ack.target_component) == (255, 190)
    got = download(env.client)
    assert len(got) == len(items)
    # item 0 comes back as the current home; RTL with frame 0 and zero coordinates
    assert (got[0].x, got[0].y) == (-353632621, 1491652374)
    assert got[-1].command == mav.MAV_CMD_NAV_RETURN_TO_LAUNCH and got[-1].frame == 0
    for it, m in zip(items[1:-1], got[1:-1]):
        for f in ("frame", "command", "autocontinue", "x", "y"):
            assert getattr(it, f) == getattr(m, f), f
        for f in ("param1", "param2", "param3", "param4", "z"):
            assert same(float(getattr(it, f)), float(getattr(m, f))), f
    # the vehicle was told, with the whole mission
    assert wait_until(lambda: env.vehicle.calls_named("mission_updated"))
    updated = env.vehicle.calls_named("mission_updated")
    assert len(updated[-1][0]) == len(items)
    # the float form (MISSION_REQUEST / MISSION_ITEM) gives degrees
    flt = download(env.client, as_int=False)
    assert abs(flt[3].x - (-35.3631621)) < 1e-6
    cur = env.client.wait("MISSION_CURRENT", lambda m: m.total == len(items) - 1, 2.5)
    assert cur is not None and cur.mission_state == mav.MISSION_STATE_NOT_STARTED


def test_upload_failures_keep_previous_mission(env):
    good = mission(2)
    assert upload(env.client, good).type == mav.MAV_MISSION_ACCEPTED
    assert wait_until(lambda: env.vehicle.calls_named("mission_updated"))
    before = env.server.missions.items()
    n_updates = len(env.vehicle.calls_named("mission_updated"))

    bad_cmd = MissionItem(3, G, mav.MAV_CMD_DO_DIGICAM_CONTROL, 0, 1)
    ack = upload(env.client, mission(3), replace={3: bad_cmd})
    assert ack.type == mav.MAV_MISSION_UNSUPPORTED

    bad_frame = MissionItem(3, mav.MAV_FRAME_LOCAL_NED, mav.MAV_CMD_NAV_WAYPOINT, 0, 1)
    ack = upload(env.client, mission(3), replace={3: bad_frame})
    assert ack.type == mav.MAV_MISSION_UNSUPPORTED_FRAME

    bad_lat = MissionItem(3, G, mav.MAV_CMD_NAV_WAYPOINT, 0, 1, x=950_000_000, y=0, z=10)
    ack = upload(env.client, mission(3), replace={3: bad_lat})
    assert ack.type == mav.MAV_MISSION_INVALID_PARAM5_X

    bad_z = MissionItem(3, G, mav.MAV_CMD_NAV_WAYPOINT, 0, 1, z=float("inf"))
    ack = upload(env.client, mission(3), replace={3: bad_z})
    assert ack.type == mav.MAV_MISSION_INVALID_PARAM7

    # wrong count: the GCS announces 4 but sends an item numbered 6
    ack = upload(env.client, mission(3), count=4, replace={2: MissionItem(
        6, G, mav.MAV_CMD_NAV_WAYPOINT, 0, 1, z=10)})
    assert ack.type == mav.MAV_MISSION_INVALID_SEQUENCE

    # too many items for the store
    env.client.drain()
    env.client.send(mav.MAVLink_mission_count_message(1, 1, 60000, 0))
    assert env.client.wait("MISSION_ACK").type == mav.MAV_MISSION_NO_SPACE

    # a mission type nobody serves
    env.client.drain()
    env.client.send(mav.MAVLink_mission_count_message(1, 1, 3, 7))
    nack = env.client.wait("MISSION_ACK")
    assert nack.type == mav.MAV_MISSION_UNSUPPORTED
    assert nack.mission_type == 7

    # the GCS goes silent mid-upload: resent requests, then OPERATION_CANCELLED
    t0 = time.monotonic()
    ack = upload(env.client, mission(3), stop_after=2, timeout_s=3.0)
    assert ack.type == mav.MAV_MISSION_OPERATION_CANCELLED
    assert time.monotonic() - t0 < 2.5
    resent = [m for m in env.client.history if m.get_type() == "MISSION_REQUEST_INT"
              and m.seq == 2]
    assert len(resent) >= 2

    assert env.server.missions.items() == before
    assert len(env.vehicle.calls_named("mission_updated")) == n_updates


def test_download_during_upload_is_denied(env):
    env.client.send(mav.MAVLink_mission_count_message(1, 1, 5, 0))
    assert env.client.wait("MISSION_REQUEST_INT") is not None
    other = env.new_client(sysid=254)
    other.send(mav.MAVLink_mission_request_list_message(1, 1, 0))
    # udpin answers the last sender, so the other client hears its own denial
    ack = other.wait("MISSION_ACK", timeout_s=1.0)
    assert ack is not None and ack.type == mav.MAV_MISSION_DENIED
    other.send(mav.MAVLink_mission_count_message(1, 1, 3, 0))
    assert other.wait("MISSION_ACK").type == mav.MAV_MISSION_DENIED
    other.close()


def test_clear_and_count_zero(env):
    assert upload(env.client, mission(1)).type == mav.MAV_MISSION_ACCEPTED
    env.client.drain()
    env.client.send(mav.MAVLink_mission_clear_all_message(1, 1, 0))
    assert env.client.wait("MISSION_ACK").type == mav.MAV_MISSION_ACCEPTED
    assert env.server.missions.count() == 1           # home slot stays
    assert wait_until(lambda: (u := env.vehicle.calls_named("mission_updated"))
                      and len(u[-1][0]) == 1)
    assert upload(env.client, mission(1)).type == mav.MAV_MISSION_ACCEPTED
    env.client.drain()
    env.client.send(mav.MAVLink_mission_count_message(1, 1, 0, 0))
    assert env.client.wait("MISSION_ACK").type == mav.MAV_MISSION_ACCEPTED
    assert env.server.missions.count() == 1
    cur = env.client.wait("MISSION_CURRENT", lambda m: m.mission_state ==
                          mav.MISSION_STATE_NO_MISSION, 2.5)
    assert cur is not None and cur.total == 0


def test_set_current_start_and_item_reached(env):
    items = mission(2)
    assert upload(env.client, items).type == mav.MAV_MISSION_ACCEPTED
    env.client.send(mav.MAVLink_mission_set_current_message(1, 1, 4))
    cur = env.client.wait("MISSION_CURRENT", lambda m: m.seq == 4)
    assert cur is not None
    assert env.vehicle.calls_named("mission_set_current") == [(4,)]
    env.client.send(mav.MAVLink_mission_set_current_message(1, 1, 99))
    st = env.client.wait("STATUSTEXT", lambda m: "99" in m.text)
    assert st is not None
    ack = env.client.command_long(mav.MAV_CMD_DO_SET_MISSION_CURRENT, p1=3)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert env.client.wait("MISSION_CURRENT", lambda m: m.seq == 3) is not None
    env.client.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=1)
    ack = env.client.command_long(mav.MAV_CMD_MISSION_START)
    assert ack.result == mav.MAV_RESULT_ACCEPTED and env.vehicle.mode == CopterMode.AUTO
    cur = env.client.wait("MISSION_CURRENT", lambda m: m.mission_state ==
                          mav.MISSION_STATE_ACTIVE, 2.5)
    assert cur is not None and cur.mission_mode == 1
    env.server.mission_item_reached(1)
    reached = env.client.wait("MISSION_ITEM_REACHED")
    assert reached is not None and reached.seq == 1


def test_wpl_file_roundtrip_through_server(env, tmp_path):
    items = mission(4)
    path = tmp_path / "m.waypoints"
    save_wpl(path, items)
    loaded = load_wpl(path)
    assert len(loaded) == len(items)
    assert all(a.same_content(b) for a, b in zip(items, loaded, strict=True))
    assert upload(env.client, loaded).type == mav.MAV_MISSION_ACCEPTED
    stored = env.server.missions.items()
    save_wpl(tmp_path / "back.waypoints", stored)
    again = load_wpl(tmp_path / "back.waypoints")
    assert all(a.same_content(b) for a, b in zip(stored, again, strict=True))
    assert path.read_text().splitlines()[0] == "QGC WPL 110"
