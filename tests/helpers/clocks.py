"""What the fake run clocks of the mover tests share: the parts of :class:`mover.RunClock` that
they do not model (a hold is only recorded, idling does nothing)."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator


class UnmodelledHold:
    """``hold`` and ``idling`` for a fake :class:`mover.RunClock` that has no world to idle in:
    the last hold asked for is kept in ``held``."""

    held: float | None = None

    def reach(self, t: float) -> float:
        """``t``: no world runs ahead."""
        return t

    def hold(self, t: float | None) -> None:
        """Record ``t`` (the time to hold at; None: no hold)."""
        self.held = t

    @contextlib.asynccontextmanager
    async def idling(self) -> AsyncIterator[None]:
        """Nothing to idle: the body runs as it is."""
        yield
