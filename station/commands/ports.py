"""``station ports``: the serial ports this machine lists, with what to type to open them."""

from __future__ import annotations

import argparse
import json

DESCRIPTION = """\
List the serial ports of this machine: device, description, the stable /dev/serial/by-id/ path
(use it: it does not change when adaptors are plugged in another order) and the USB VID:PID
(usable as hwgrep://VID:PID). Pseudo-terminals (/dev/pts/N, e.g. `station simulate --pty`) and
network URLs (rfc2217://HOST:PORT, socket://HOST:PORT) are never listed but open all the same.
"""

NOT_LISTED = (
    "Pseudo-terminals (/dev/pts/N) and network ports (rfc2217://HOST:PORT, socket://HOST:PORT) "
    "are not listed but work with --port."
)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station ports``."""
    parser = subparsers.add_parser(
        "ports",
        help="list the serial ports (device, description, by-id path, VID:PID)",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--json", action="store_true", help="one JSON object per port per line")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the ports; a sentence when there are none."""
    from station.instruments.transport import list_ports

    ports = list_ports()
    if args.json:
        for port in ports:
            print(json.dumps(port.__dict__), flush=True)
        return 0
    if not ports:
        print("No serial ports found: plug the USB-serial adaptor in and check `dmesg | tail`.")
        print(NOT_LISTED)
        return 0
    header = ("DEVICE", "VID:PID", "DESCRIPTION", "BY-ID PATH")
    rows = [(p.device, p.vid_pid or "-", p.description or "-", p.by_id or "-") for p in ports]
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(3)]
    for row in [header, *rows]:
        print(
            "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=False))
            + "  "
            + row[3]
        )
    print(NOT_LISTED)
    return 0
