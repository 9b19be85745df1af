"""The benchmark client gives up on a vehicle that is gone: a command waiting for its ack
ends with Failed when the run is interrupted or the vehicle went silent, instead of
resending forever on a clock (the vehicle's time_boot_ms) that no longer moves. Once, a
crashed `silbridge fly` left `bench --suite failures` spinning past its timeout."""

from __future__ import annotations

import pytest

from silbridge.tools.benchmark.nav import client as nav_client
from silbridge.tools.benchmark.nav.client import Failed, NavClient
from silbridge.tools.benchmark.nav.link import UdpLink, free_udp_port


class _Stop:
    requested = False


def test_an_interrupted_command_ends_instead_of_resending_forever():
    link = UdpLink(free_udp_port())          # nobody talks on it: the vehicle is gone
    stop = _Stop()
    c = NavClient(link, 47.0, 8.0, stop=stop)
    c.sysid = 1
    try:
        c.pump(0.01)                          # an ordinary pump: nothing heard, no error
        stop.requested = True
        with pytest.raises(Failed, match="interrupted"):
            c.command(400, 1)
    finally:
        link.close()


def test_a_silent_vehicle_ends_a_command(monkeypatch):
    monkeypatch.setattr(nav_client, "SILENT_WALL_S", 0.3)
    link = UdpLink(free_udp_port())
    c = NavClient(link, 47.0, 8.0)
    c.sysid = 1
    try:
        with pytest.raises(Failed, match="said nothing"):
            c.command(400, 1)
    finally:
        link.close()
