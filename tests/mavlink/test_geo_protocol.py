"""Fence and rally lists over the MISSION_* protocol (mission_type 1 and 2), at the server:
upload with every item checked, download as stored, MISSION_ITEM (float) uploads, the
whole-or-nothing rule (a bad or abandoned upload keeps the old list), clear per type and
MAV_MISSION_TYPE_ALL, RALLY_TOTAL, the vehicle told of each new list; and SRn_* stream rates
(a REQUEST_DATA_STREAM stores them, a new link starts with them)."""

from __future__ import annotations

import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from mavtest_client import GcsClient, wait_until

from silbridge.mavlink.gcs.geo_store import GeoStore, check_list
from silbridge.mavlink.gcs.vehicle_api import MissionItem

FENCE, RALLY = mav.MAV_MISSION_TYPE_FENCE, mav.MAV_MISSION_TYPE_RALLY
G = mav.MAV_FRAME_GLOBAL_INT
INCL, EXCL = (mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
              mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION)
LAT, LON = -353632621, 1491652374


def fence_items() -> list[MissionItem]:
    sq = [(-4000, -4000), (4000, -4000), (4000, 4000), (-4000, 4000)]
    items = [MissionItem(i, G, INCL, param1=4, x=LAT + n, y=LON + e, mission_type=FENCE)
             for i, (n, e) in enumerate(sq)]
    items += [MissionItem(4 + i, G, EXCL, param1=3, x=LAT + n, y=LON + e, mission_type=FENCE)
              for i, (n, e) in enumerate([(1000, 1000), (2000, 1000), (1500, 2000)])]
    items.append(MissionItem(7, G, mav.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, param1=12.5,
                             x=LAT - 2000, y=LON - 2000, mission_type=FENCE))
    return items


def rally_items() -> list[MissionItem]:
    return [MissionItem(i, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mav.MAV_CMD_NAV_RALLY_POINT,
                        x=LAT + 3000 * i, y=LON, z=15.0 + i, mission_type=RALLY)
            for i in range(3)]


def upload(client, items, mtype, *, as_float=False, stop_after=None, timeout_s=2.0):
    client.drain()
    client.send(mav.MAVLink_mission_count_message(1, 1, len(items), mtype))
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for m in client.pump(0.05):
            t = m.get_type()
            if t == "MISSION_ACK":
                return m
            if t in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
                if stop_after is not None and m.seq >= stop_after:
                    continue
                it = items[m.seq]
                if as_float:
                    client.send(mav.MAVLink_mission_item_message(
                        1, 1, it.seq, mav.MAV_FRAME_GLOBAL, it.command, 0, 1, it.param1,
                        it.param2, it.param3, it.param4, it.x / 1e7, it.y / 1e7, it.z, mtype))
                else:
                    client.send(mav.MAVLink_mission_item_int_message(
                        1, 1, it.seq, it.frame, it.command, 0, 1, it.param1, it.param2,
                        it.param3, it.param4, it.x, it.y, it.z, mtype))
    return None


def download(client, mtype):
    client.drain()
    client.send(mav.MAVLink_mission_request_list_message(1, 1, mtype))
    cnt = client.wait("MISSION_COUNT")
    out = []
    for seq in range(cnt.count):
        client.send(mav.MAVLink_mission_request_int_message(1, 1, seq, mtype))
        out.append(client.wait("MISSION_ITEM_INT", lambda m, s=seq: m.seq == s))
    return out


def same(sent, got):
    assert len(sent) == len(got)
    for s, g in zip(sent, got):
        assert (g.command, g.x, g.y, g.param1, g.mission_type) == \
            (s.command, s.x, s.y, s.param1, s.mission_type)
        assert abs(g.z - s.z) < 1e-4


def test_fence_and_rally_round_trip_and_vehicle_told(env):
    ack = upload(env.client, fence_items(), FENCE)
    assert ack.type == mav.MAV_MISSION_ACCEPTED and ack.mission_type == FENCE
    same(fence_items(), download(env.client, FENCE))
    ack = upload(env.client, rally_items(), RALLY, as_float=True)
    assert ack.type == mav.MAV_MISSION_ACCEPTED
    got = download(env.client, RALLY)
    assert [g.command for g in got] == [mav.MAV_CMD_NAV_RALLY_POINT] * 3
    # float32 degrees carry ~7 digits: a few 1e-7 deg (centimetres) of rounding
    assert all(abs(g.x - s.x) <= 50 for g, s in zip(got, rally_items())), got
    assert env.params.get("RALLY_TOTAL")[0] == 3
    assert wait_until(lambda: len(env.vehicle.calls_named("geo_updated")) >= 2, 2.0)
    assert [c[0] for c in env.vehicle.calls_named("geo_updated")][-2:] == [FENCE, RALLY]
    # the mission is untouched by both
    env.client.send(mav.MAVLink_mission_request_list_message(1, 1, 0))
    assert env.client.wait("MISSION_COUNT", lambda m: m.mission_type == 0).count == 1


def test_bad_or_abandoned_fence_upload_keeps_the_old_one(env):
    assert upload(env.client, fence_items(), FENCE).type == mav.MAV_MISSION_ACCEPTED
    bad = fence_items()
    bad[2] = MissionItem(2, G, INCL, param1=5, x=LAT, y=LON, mission_type=FENCE)
    ack = upload(env.client, bad, FENCE)
    assert ack.type == mav.MAV_MISSION_INVALID_PARAM1
    short = fence_items()[:3]                       # a polygon of 4 with 3 vertices
    ack = upload(env.client, short, FENCE)
    assert ack.type == mav.MAV_MISSION_INVALID
    circle = [MissionItem(0, G, mav.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, param1=-3, x=LAT, y=LON,
                          mission_type=FENCE)]
    assert upload(env.client, circle, FENCE).type == mav.MAV_MISSION_INVALID_PARAM1
    wp = [MissionItem(0, G, mav.MAV_CMD_NAV_WAYPOINT, x=LAT, y=LON, mission_type=FENCE)]
    assert upload(env.client, wp, FENCE).type == mav.MAV_MISSION_UNSUPPORTED
    local = [MissionItem(0, mav.MAV_FRAME_LOCAL_NED, mav.MAV_CMD_NAV_RALLY_POINT,
                         mission_type=RALLY)]
    assert upload(env.client, local, RALLY).type == mav.MAV_MISSION_UNSUPPORTED_FRAME
    ack = upload(env.client, fence_items(), FENCE, stop_after=3, timeout_s=3.0)
    assert ack.type == mav.MAV_MISSION_OPERATION_CANCELLED
    same(fence_items(), download(env.client, FENCE))


def test_clear_per_type_and_all(env):
    assert upload(env.client, fence_items(), FENCE).type == mav.MAV_MISSION_ACCEPTED
    assert upload(env.client, rally_items(), RALLY).type == mav.MAV_MISSION_ACCEPTED
    env.client.drain()
    env.client.send(mav.MAVLink_mission_clear_all_message(1, 1, FENCE))
    assert env.client.wait("MISSION_ACK").type == mav.MAV_MISSION_ACCEPTED
    assert download(env.client, FENCE) == []
    assert len(download(env.client, RALLY)) == 3
    env.client.drain()
    env.client.send(mav.MAVLink_mission_clear_all_message(1, 1, mav.MAV_MISSION_TYPE_ALL))
    assert env.client.wait("MISSION_ACK").type == mav.MAV_MISSION_ACCEPTED
    assert download(env.client, RALLY) == []
    assert env.params.get("RALLY_TOTAL")[0] == 0


def test_geo_store_rules():
    assert check_list(FENCE, fence_items()) == (mav.MAV_MISSION_ACCEPTED, -1)
    items = fence_items()
    items.insert(2, MissionItem(2, G, mav.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, param1=5, x=LAT,
                                y=LON, mission_type=FENCE))
    items = [MissionItem(i, it.frame, it.command, param1=it.param1, x=it.x, y=it.y)
             for i, it in enumerate(items)]
    assert check_list(FENCE, items)[0] == mav.MAV_MISSION_INVALID_SEQUENCE   # mid-polygon
    store = GeoStore(RALLY, capacity=2)
    assert store.replace(rally_items()) == mav.MAV_MISSION_NO_SPACE
    assert store.count() == 0


def test_stream_rates_are_remembered_per_endpoint(env):
    cl = env.client
    cl.send(mav.MAVLink_request_data_stream_message(1, 1, mav.MAV_DATA_STREAM_ALL, 4, 1))
    assert wait_until(lambda: env.params.get("SR0_POSITION")[0] == 4, 2.0)
    assert env.params.get("SR0_EXTRA1")[0] == 4
    # a start without a rate is ignored, as ArduCopter does
    cl.send(mav.MAVLink_request_data_stream_message(1, 1, mav.MAV_DATA_STREAM_POSITION, 0, 1))
    time.sleep(0.3)
    assert env.params.get("SR0_POSITION")[0] == 4


def test_a_new_link_starts_with_the_stored_rates(make_env):
    e = make_env(endpoints=["tcpin:127.0.0.1:0"])
    e.params.set("SR0_POSITION", 5)
    addr = next(iter(e.server.local_addresses().values()))
    import socket
    s = socket.create_connection(addr)
    try:
        mavc = mav.MAVLink(None)
        mavc.robust_parsing = True
        s.settimeout(0.2)
        seen = 0
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            try:
                data = s.recv(65536)
            except socket.timeout:
                continue
            seen += sum(1 for m in mavc.parse_buffer(data) or []
                        if m.get_type() == "GLOBAL_POSITION_INT")
        assert 5 <= seen <= 20, seen          # 5 Hz for 2 s, nobody asked on this link
    finally:
        s.close()
