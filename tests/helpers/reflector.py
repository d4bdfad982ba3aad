"""A hostile process with no team key that reflects the team's frames back at it.

``python -m tests.helpers.reflector TEAM --seconds S``: one raw zenoh session (peer mode, the
cluster's endpoints from the environment) that

* declares queryables on every member's call and hello keys; each query it gets (a member's
  call, a challenge) it asks again of the members at once, the same frame, and hands every
  answer it gets back as its own answer to the first query — the relay by which an outsider
  once turned a callee's sealed "replayed" refusal into a failed call (issue 24);
* puts again, once, every frame it hears on the team's control and broadcast keys (a caller's
  cancel, a broadcast).

With ``--first`` it plays the other race (issue 24, "copy first, drop the answer"): it
declares queryables on the members' call keys only, sends each call it gets on to the members
at once (to reach the callee before the original, it must have the faster path: the test
gives it one), and answers nothing, dropping whatever the callee answers its copy. A callee
that ran the copy and then refused the original as a replay would leave the real call without
an answer. ``<answers>`` then counts sealed answers to its copies (the callee ran the copy
first) and ``<refusals>`` unsigned refusals (the original came first). ``--copies N`` sends N
copies of each call (more than a callee holds for one running call crowd the original out).

It prints ``READY`` once declared and ``DONE <queries> <answers> <puts> <refusals>`` when it
stops (after ``--seconds``, or at SIGTERM).
"""

from __future__ import annotations

import argparse
import signal
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import zenoh

from mover import NodeConfig


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("team")
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--first", action="store_true", help="copy each call first, drop answers")
    p.add_argument("--copies", type=int, default=1, help="with --first: copies of each call")
    args = p.parse_args()
    session = zenoh.open(NodeConfig.from_env().to_zenoh())
    pool = ThreadPoolExecutor(32)  # a long call must not hold the others up
    counts = {"queries": 0, "answers": 0, "puts": 0, "refusals": 0}
    mine: set[bytes] = set()  # frames it put itself (heard again: not put a third time)
    lock = threading.Lock()

    def relay(query: Any) -> None:
        frame = bytes(query.payload.to_bytes()) if query.payload is not None else b""
        replies = session.get(
            str(query.key_expr),
            payload=frame,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
            allowed_destination=zenoh.Locality.REMOTE,  # not its own queryables
            timeout=30.0,
        )
        with query:
            for reply in replies:
                if reply.ok is not None:
                    query.reply(reply.ok.key_expr, bytes(reply.ok.payload.to_bytes()))
                    with lock:
                        counts["answers"] += 1

    def on_query(query: Any) -> None:
        with lock:
            counts["queries"] += 1
        pool.submit(relay, query)

    def on_answer(reply: Any) -> None:
        if reply.ok is None:
            return
        kind = "answers" if bytes(reply.ok.payload.to_bytes()[:2]) == b"M2" else "refusals"
        with lock:
            counts[kind] += 1

    def first(query: Any) -> None:
        frame = bytes(query.payload.to_bytes()) if query.payload is not None else b""
        for _ in range(args.copies):  # at once, from zenoh's thread: no hop through a pool
            session.get(
                str(query.key_expr),
                payload=frame,
                target=zenoh.QueryTarget.ALL,
                consolidation=zenoh.ConsolidationMode.NONE,
                allowed_destination=zenoh.Locality.REMOTE,
                timeout=30.0,
                handler=on_answer,
            )
        with lock:
            counts["queries"] += 1
        query.drop()  # the caller's query ends with no answer from here

    def on_sample(sample: Any) -> None:
        frame = bytes(sample.payload.to_bytes())
        with lock:
            if frame in mine:
                return
            mine.add(frame)
            counts["puts"] += 1
        pool.submit(session.put, str(sample.key_expr), frame)

    team = f"mover/{args.team}"
    if args.first:
        declared: list[Any] = [session.declare_queryable(f"{team}/rpc/**", first)]
    else:
        declared = [
            session.declare_queryable(f"{team}/rpc/**", on_query),
            session.declare_queryable(f"{team}/hello/**", on_query),
            session.declare_subscriber(f"{team}/ctl/**", on_sample),
            session.declare_subscriber(f"{team}/bc/**", on_sample),
        ]
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    print("READY", flush=True)
    stop.wait(args.seconds)
    for entity in declared:
        entity.undeclare()
    pool.shutdown(wait=False, cancel_futures=True)
    session.close()
    print("DONE", *counts.values(), flush=True)


if __name__ == "__main__":
    main()
