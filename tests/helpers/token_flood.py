"""An outsider with no team key that declares many fake liveliness tokens under a team's prefix.

``python -m tests.helpers.token_flood TEAM --tokens N --seconds S [--answer] [--also NAME]``:
one raw zenoh session (peer mode, the cluster's endpoints from the environment) declares N
tokens ``mover/TEAM/alive/fake-<i>`` (and one of each ``--also`` name: a member's own), prints
``READY`` once declared, holds them S seconds, then undeclares them and prints ``DONE``. With
``--answer`` it also answers every hello question on the team's prefix with junk (so that each
fake token also earns a refused hello).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import zenoh

from mover import NodeConfig


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("team")
    p.add_argument("--tokens", type=int, default=2000)
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--answer", action="store_true")
    p.add_argument("--also", action="append", default=[], metavar="NAME")
    args = p.parse_args()

    def on_query(query: Any) -> None:
        with query:
            query.reply(query.key_expr, b"MRnot a hello")

    session = zenoh.open(NodeConfig.from_env().to_zenoh())
    answering = (
        session.declare_queryable(f"mover/{args.team}/hello/**", on_query) if args.answer else None
    )
    names = [f"fake-{i}" for i in range(args.tokens)] + args.also
    tokens = [session.liveliness().declare_token(f"mover/{args.team}/alive/{n}") for n in names]
    print("READY", flush=True)
    time.sleep(args.seconds)
    for token in tokens:
        token.undeclare()
    if answering is not None:
        answering.undeclare()
    session.close()
    print("DONE", flush=True)


if __name__ == "__main__":
    main()
