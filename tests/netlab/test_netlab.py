"""The lab of hosts (network namespaces) leaves nothing behind: not when its body ends, raises,
is interrupted (Ctrl-C) or is SIGKILLed (the next lab sweeps)."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from mover.testing import Netlab
from tests.helpers.procs import ROOT
from tests.netlab import LAB

pytestmark = LAB

CONNECT = "import socket,sys; socket.create_connection((sys.argv[1], 9000), timeout=3).close()"
SERVE = textwrap.dedent(
    """
    import socket, subprocess, sys, time
    s = socket.create_server((sys.argv[1], 9000))
    subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])  # a grandchild
    print("up", flush=True)
    while True:
        s.accept()[0].close()
    """
)


def names_now() -> str:
    out = subprocess.run(
        "ip netns list; ip -o link show", shell=True, capture_output=True, text=True, check=False
    )
    return out.stdout


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:  # a zombie is dead, waiting to be reaped
        return f.read().rsplit(")", 1)[1].split()[0] != "Z"


async def ns_pids(ns: str) -> list[int]:
    proc = await asyncio.create_subprocess_exec(
        "ip", "netns", "pids", ns, stdout=asyncio.subprocess.PIPE
    )
    out, _ = await proc.communicate()
    return [int(p) for p in out.split()]


async def use_then_fail(lab: Netlab, pids: list[int]) -> None:
    """Serve in a, connect from b, cut b off and plug it in, stop a process in c; then raise."""
    async with lab:
        a = lab["a"].address
        server = await lab.start("a", [sys.executable, "-c", SERVE, a])
        assert server.proc.stdout is not None
        assert await asyncio.wait_for(server.proc.stdout.readline(), 10) == b"up\n"
        assert (await lab.run("b", sys.executable, "-c", CONNECT, a))[0] == 0
        stopped = await lab.start("c", [sys.executable, "-c", "import time; time.sleep(600)"])
        os.kill(stopped.proc.pid, signal.SIGSTOP)  # a stopped process must die too
        pids += [*await ns_pids(lab["a"].ns), stopped.proc.pid]
        assert len(pids) >= 3  # the server, its grandchild, the stopped one
        async with lab.partition("b"):
            code, said = await lab.run("b", sys.executable, "-c", CONNECT, a)
            assert code != 0 and "timed out" in said
        assert (await lab.run("b", sys.executable, "-c", CONNECT, a))[0] == 0
        assert lab.leftovers()
        raise RuntimeError("the body failed")


async def test_hosts_reach_each_other_a_partition_cuts_one_off_and_a_raise_leaves_nothing() -> None:
    lab = Netlab(("a", "b", "c"))
    pids: list[int] = []
    with pytest.raises(RuntimeError, match="the body failed"):
        await use_then_fail(lab, pids)
    assert lab.leftovers() == []
    assert lab.tag not in names_now()
    assert [p for p in pids if alive(p)] == []
    lab.close()  # again: nothing to do, no error


LAB_THEN_WAIT = textwrap.dedent(
    """
    import asyncio, signal, sys
    from mover.testing import Netlab

    signal.signal(signal.SIGINT, signal.default_int_handler)  # as at a terminal (CI may ignore it)

    async def main():
        async with Netlab(("a", "b")) as lab:
            await lab.start("b", [sys.executable, "-c", "import time; time.sleep(600)"])
            print(lab.tag, flush=True)
            await asyncio.sleep(600)

    asyncio.run(main())
    """
)


async def lab_in_a_process() -> tuple[asyncio.subprocess.Process, str]:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-c", LAB_THEN_WAIT, cwd=ROOT, stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )  # fmt: skip
    assert proc.stdout is not None
    tag = (await asyncio.wait_for(proc.stdout.readline(), 20)).decode().strip()
    assert tag and tag in names_now()
    return proc, tag


async def test_ctrl_c_tears_the_lab_down_and_a_killed_labs_leftovers_are_swept() -> None:
    proc, tag = await lab_in_a_process()
    proc.send_signal(signal.SIGINT)
    _, err = await asyncio.wait_for(proc.communicate(), 20)
    assert b"KeyboardInterrupt" in err  # asyncio.run's own word; the lab closed on the way out
    assert tag not in names_now()

    proc, tag = await lab_in_a_process()
    proc.kill()  # no chance to clean up: its namespaces and its sleeper stay
    await proc.wait()
    assert tag in names_now()
    async with Netlab(("x",)) as other:  # a new lab sweeps what a dead one left
        assert tag not in names_now()
        assert other.tag in names_now()
    assert other.tag not in names_now()
