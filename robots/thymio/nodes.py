"""``python -m robots.thymio.nodes LINK``: the Aseba nodes that answer on a link, one a line.

``LINK`` is what ``--option link=`` takes: ``tcp:HOST:PORT`` (an ``asebaswitch``, a
Playground robot) or a serial device. Each line is ``node ID: NAME``; the ids are what
``--option node=ID`` takes when several robots share one link (a wireless dongle behind
``asebaswitch``). Exit status 1, with one line, if nothing answers.
"""

from __future__ import annotations

import argparse
import asyncio
import sys

from robots.hal import HardwareLost

from ._link import Address, list_nodes


def main(argv: list[str] | None = None) -> int:
    """List the nodes on the link of ``argv`` (see the module docstring)."""
    p = argparse.ArgumentParser(prog="python -m robots.thymio.nodes", description=__doc__)
    p.add_argument("link", help="tcp:HOST:PORT or a serial device")
    p.add_argument("--wait", type=float, default=1.0, help="seconds to listen (default 1)")
    args = p.parse_args(argv)
    try:
        address = Address.parse(args.link)
        nodes = asyncio.run(list_nodes(address, args.wait))
    except (ValueError, HardwareLost) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    if not nodes:
        print(f"error: no Aseba node answered at {address} within {args.wait:g} s", file=sys.stderr)
        return 1
    for node, name in nodes.items():
        print(f"node {node}: {name or '(no description)'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
