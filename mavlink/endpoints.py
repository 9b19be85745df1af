"""GCS endpoint URLs: parsing, defaults and the shared --gcs command-line option.

Three forms, as ArduPilot SITL users write them:
  udpout:HOST:PORT   send telemetry to HOST:PORT (a GCS listening there), answer what comes back
  udpin:HOST:PORT    listen on HOST:PORT, reply to the address of the last valid sender
  tcpin:HOST:PORT    listen for TCP clients, each connection is its own link
Default: udpout to 127.0.0.1:14550 (QGC, MAVProxy) and 127.0.0.1:14540 (MAVSDK). Listening
endpoints bind exactly the HOST given, so loopback stays loopback unless the user writes
0.0.0.0. PORT 0 asks the kernel for a free port (tests).
"""

from __future__ import annotations

import argparse
import ipaddress
from dataclasses import dataclass

from silbridge.mavlink.errors import EndpointError

KINDS = ("udpout", "udpin", "tcpin")
DEFAULT_GCS_URLS = ("udpout:127.0.0.1:14550", "udpout:127.0.0.1:14540")


@dataclass(frozen=True, slots=True)
class Endpoint:
    kind: str      # one of KINDS
    host: str
    port: int

    @property
    def url(self) -> str:
        return f"{self.kind}:{self.host}:{self.port}"

    @property
    def is_loopback(self) -> bool:
        if self.host == "localhost":
            return True
        try:
            return ipaddress.ip_address(self.host).is_loopback
        except ValueError:
            return False


def parse_endpoint(url: str) -> Endpoint:
    """Parse "KIND:HOST:PORT" (a "KIND://HOST:PORT" spelling is accepted too)."""
    text = url.strip().replace("://", ":", 1)
    parts = text.split(":")
    if len(parts) != 3 or parts[0] not in KINDS:
        raise EndpointError(
            f"cannot parse GCS endpoint {url!r}: write udpout:HOST:PORT, udpin:HOST:PORT "
            f"or tcpin:HOST:PORT (e.g. udpout:127.0.0.1:14550)")
    kind, host, port_text = parts
    if not host:
        raise EndpointError(f"GCS endpoint {url!r} has no host: use 127.0.0.1 (or 0.0.0.0 "
                            f"to listen on every interface)")
    try:
        port = int(port_text)
    except ValueError:
        raise EndpointError(f"GCS endpoint {url!r}: port {port_text!r} is not a number") from None
    if not 0 <= port <= 65535 or (kind == "udpout" and port == 0):
        raise EndpointError(f"GCS endpoint {url!r}: port must be 1..65535 "
                            f"(0 only for udpin/tcpin, meaning any free port)")
    return Endpoint(kind, host, port)


def parse_endpoints(urls: list[str] | tuple[str, ...] | None) -> list[Endpoint]:
    return [parse_endpoint(u) for u in (urls if urls else DEFAULT_GCS_URLS)]


def add_gcs_arguments(parser: argparse.ArgumentParser) -> None:
    """The --gcs / --no-default-gcs options shared by `silbridge fc` and `silbridge fly`."""
    parser.add_argument(
        "--gcs", metavar="URL", action="append", default=[],
        help="extra MAVLink endpoint: udpout:HOST:PORT, udpin:HOST:PORT or tcpin:HOST:PORT "
             "(repeatable; defaults udpout:127.0.0.1:14550 and :14540 are always added "
             "unless --no-default-gcs)")
    parser.add_argument(
        "--no-default-gcs", action="store_true",
        help="do not send to the default endpoints 127.0.0.1:14550 and 127.0.0.1:14540")


def endpoints_from_args(args: argparse.Namespace) -> list[Endpoint]:
    urls = [] if getattr(args, "no_default_gcs", False) else list(DEFAULT_GCS_URLS)
    for url in getattr(args, "gcs", []) or []:
        if url not in urls:
            urls.append(url)
    return [parse_endpoint(u) for u in urls]
