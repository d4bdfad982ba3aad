"""What rerun makes of an MCAP file: its own importer (``rerun mcap convert``, the one its
viewer runs on a file it opens) to an ``.rrd``, then ``rerun rrd print``'s chunk list."""

from __future__ import annotations

import importlib.util
import re
import subprocess
from pathlib import Path

CHUNK = re.compile(r"^Chunk\(\S+\) with (\d+) rows \(.*\) - (\S+) - data columns: \[(.*)\]$")


def rerun_program() -> Path | None:
    """The ``rerun`` program of the ``rerun-sdk`` wheel (the view extra), or None."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is None or spec.origin is None:
        return None
    exe = Path(spec.origin).parent / "rerun"
    return exe if exe.is_file() else None


def rerun_entities(mcap: Path, rrd: Path) -> dict[str, dict[str, int]]:
    """Per entity path, the rows rerun holds under each archetype it converted to (``Mcap*``
    bookkeeping columns left out), after converting ``mcap`` to ``rrd``."""
    exe = rerun_program()
    assert exe is not None
    run = [str(exe), "mcap", "convert", str(mcap), "-o", str(rrd), "--timeline-type", "duration"]
    subprocess.run(run, check=True, capture_output=True, timeout=120)
    printed = subprocess.run(
        [str(exe), "rrd", "print", str(rrd)],
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    got: dict[str, dict[str, int]] = {}
    for line in printed.splitlines():
        m = CHUNK.match(line.strip())
        if m is None:
            continue
        rows, entity, columns = int(m[1]), m[2], m[3].split()
        kinds = {c.split(":")[0] for c in columns if not c.startswith("Mcap")}
        for kind in kinds:
            got.setdefault(entity, {})[kind] = got.get(entity, {}).get(kind, 0) + rows
    return got
