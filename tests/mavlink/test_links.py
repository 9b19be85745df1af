"""Endpoints and links: URL parsing, defaults, loopback binding, udpout and tcpin serving."""

from __future__ import annotations

import argparse
import socket

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from mavtest_client import GcsClient

from silbridge.mavlink.endpoints import (DEFAULT_GCS_URLS, add_gcs_arguments,
                                         endpoints_from_args, parse_endpoint)
from silbridge.mavlink.errors import EndpointError


def test_parse_endpoints():
    e = parse_endpoint("udpout:127.0.0.1:14550")
    assert (e.kind, e.host, e.port) == ("udpout", "127.0.0.1", 14550) and e.is_loopback
    assert parse_endpoint("tcpin://0.0.0.0:5760").url == "tcpin:0.0.0.0:5760"
    assert not parse_endpoint("udpin:0.0.0.0:14550").is_loopback
    for bad in ("udp:1.2.3.4:5", "udpout:127.0.0.1", "udpout:127.0.0.1:x", "tcpin::5760",
                "udpout:127.0.0.1:0", "udpin:127.0.0.1:70000"):
        with pytest.raises(EndpointError) as exc:
            parse_endpoint(bad)
        assert exc.value.user_facing


def test_cli_arguments_add_to_defaults():
    p = argparse.ArgumentParser()
    add_gcs_arguments(p)
    urls = [e.url for e in endpoints_from_args(p.parse_args(["--gcs", "tcpin:127.0.0.1:5760"]))]
    assert urls == list(DEFAULT_GCS_URLS) + ["tcpin:127.0.0.1:5760"]
    only = endpoints_from_args(p.parse_args(["--no-default-gcs", "--gcs", "udpin:127.0.0.1:1"]))
    assert [e.url for e in only] == ["udpin:127.0.0.1:1"]


def test_udpout_sends_heartbeats_and_answers_from_its_port(make_env):
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gcs.bind(("127.0.0.1", 0))
    port = gcs.getsockname()[1]
    e = make_env(endpoints=[f"udpout:127.0.0.1:{port}"])
    gcs.settimeout(3.0)
    parser = mav.MAVLink(None)
    hb = None
    while hb is None:
        data, server_addr = gcs.recvfrom(65535)
        hb = next((m for m in parser.parse_buffer(data) or [] if m.get_type() == "HEARTBEAT"),
                  None)
    assert server_addr[0] == "127.0.0.1"               # loopback target -> loopback socket
    assert hb.get_type() == "HEARTBEAT" and hb.get_srcSystem() == 1
    assert hb.autopilot == mav.MAV_AUTOPILOT_ARDUPILOTMEGA
    gcs.close()
    client = GcsClient(server_addr)                     # a GCS replying to the source port
    client.sock.close()
    client.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.sock.bind(("127.0.0.1", port))
    client.sock.setblocking(False)
    ack = client.command_long(mav.MAV_CMD_REQUEST_MESSAGE, p1=mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED
    client.close()


def test_tcpin_clients_each_get_their_own_link(make_env):
    e = make_env(endpoints=["tcpin:127.0.0.1:0"])
    addr = next(iter(e.server.local_addresses().values()))
    socks = [socket.create_connection(addr) for _ in range(2)]
    try:
        for s in socks:
            s.settimeout(3.0)
            parser = mav.MAVLink(None)
            msgs = []
            while not msgs:
                msgs = [m for m in parser.parse_buffer(s.recv(4096)) or []
                        if m.get_type() == "HEARTBEAT"]
            assert msgs[0].get_srcSystem() == 1
        assert e.server.counters()["links"] == 2
        socks[0].close()
        codec = mav.MAVLink(None, srcSystem=255, srcComponent=190)
        socks[1].sendall(mav.MAVLink_command_long_message(
            1, 1, mav.MAV_CMD_NAV_LAND, 0, 0, 0, 0, 0, 0, 0, 0).pack(codec))
        parser = mav.MAVLink(None)
        ack = None
        while ack is None:
            for m in parser.parse_buffer(socks[1].recv(4096)) or []:
                if m.get_type() == "COMMAND_ACK":
                    ack = m
        assert ack.result == mav.MAV_RESULT_ACCEPTED
    finally:
        for s in socks:
            s.close()


def test_port_in_use_is_a_user_facing_error(make_env):
    busy = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    port = busy.getsockname()[1]
    try:
        with pytest.raises(EndpointError) as exc:
            make_env(endpoints=[f"tcpin:127.0.0.1:{port}"])
        assert "pick another port" in str(exc.value)
    finally:
        busy.close()
