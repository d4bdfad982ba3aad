"""A hostile process with no team key: raw zenoh sessions that try to take over a member's calls.

``python -m tests.helpers.hijacker TEAM TARGET --sessions N --seconds S --out FILE``: opens N
raw zenoh sessions (peer mode, the cluster's endpoints from the environment), each declaring a
*complete* queryable on ``mover/TEAM/rpc/TARGET`` and a subscriber on every team broadcast; it
answers every query it gets with an unsigned refusal (or, with ``--hold``, keeps it open without
answering), closes and re-declares them every half second, and writes everything it overheard
(query payloads and broadcast frames, each after a ``q`` or a ``b``) to FILE as hex lines.
Prints ``READY`` once declared and ``DONE`` when it stops.
"""

from __future__ import annotations

import argparse
import threading
import time
from typing import Any

import zenoh

from mover import NodeConfig


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("team")
    p.add_argument("target")
    p.add_argument("--sessions", type=int, default=3)
    p.add_argument("--seconds", type=float, default=3.0)
    p.add_argument("--hold", action="store_true")
    p.add_argument("--out", required=True)
    args = p.parse_args()
    heard: list[bytes] = []
    held: list[Any] = []
    lock = threading.Lock()

    def on_query(query: Any) -> None:
        with lock:
            heard.append(b"q" + (bytes(query.payload.to_bytes()) if query.payload else b""))
        if args.hold:
            held.append(query)  # never answered, never dropped: the caller's wait is its own
            return
        with query:
            query.reply(query.key_expr, b"MRhijacked: the member is busy")

    def on_sample(sample: Any) -> None:
        with lock:
            heard.append(b"b" + bytes(sample.payload.to_bytes()))

    conf = NodeConfig.from_env().to_zenoh()
    key = f"mover/{args.team}/rpc/{args.target}"
    sessions = [zenoh.open(conf) for _ in range(args.sessions)]
    end = time.monotonic() + args.seconds
    first = True
    while time.monotonic() < end:
        queryables: list[zenoh.Queryable[None]] = []
        subscribers: list[zenoh.Subscriber[None]] = []
        for s in sessions:
            queryables.append(s.declare_queryable(key, on_query, complete=True))
            subscribers.append(s.declare_subscriber(f"mover/{args.team}/bc/**", on_sample))
        if first:
            print("READY", flush=True)
            first = False
        time.sleep(0.5)
        for q, sub in zip(queryables, subscribers, strict=True):
            q.undeclare()
            sub.undeclare()
    held.clear()
    for s in sessions:
        s.close()
    with open(args.out, "w", encoding="ascii") as f:
        for frame in heard:
            f.write(frame.hex() + "\n")
    print("DONE", len(heard), flush=True)


if __name__ == "__main__":
    main()
