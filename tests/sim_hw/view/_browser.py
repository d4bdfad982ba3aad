"""Headless Chromium driven over the DevTools protocol on a pipe (no extra package).

``chromium --remote-debugging-pipe`` reads commands on its fd 3 and writes answers on fd 4, each
a JSON object ended by a NUL byte. :func:`screenshots` opens a page and takes screenshots until
one satisfies a test, or a deadline passes. SwiftShader renders the WebGL/WebGPU canvas.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import io
import json
import os
import shutil
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

BROWSERS = ("chromium", "chromium-browser", "google-chrome")
ENOUGH = 100  # pixels of a robot's colour: a disc of ~12 px radius has ~450


def find_browser() -> str | None:
    """The first headless-capable Chromium on PATH."""
    for name in BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    return None


class Browser:
    """A headless Chromium and one page, driven by DevTools commands."""

    def __init__(self, exe: str, profile: Path, size: tuple[int, int] = (1280, 800)) -> None:
        to_chrome_r, self._to_chrome = os.pipe()
        self._from_chrome, from_chrome_w = os.pipe()
        self.proc = subprocess.Popen(
            [
                exe,
                "--headless=new",
                "--no-sandbox",  # as root in CI
                "--enable-unsafe-swiftshader",
                "--use-angle=swiftshader",
                "--remote-debugging-pipe",
                f"--user-data-dir={profile}",
                f"--window-size={size[0]},{size[1]}",
                "--no-first-run",
                "--disable-gpu-sandbox",
                "about:blank",
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(3, 4),
            preexec_fn=_pipes(to_chrome_r, from_chrome_w),
        )
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self._buf = b""
        self._id = 0
        self.session: str | None = None

    def send(self, method: str, params: dict[str, Any] | None = None, timeout: float = 30.0) -> Any:
        """One command; its result (RuntimeError on an error answer)."""
        self._id += 1
        msg: dict[str, Any] = {"id": self._id, "method": method, "params": params or {}}
        if self.session is not None and not method.startswith(("Target.", "Browser.")):
            msg["sessionId"] = self.session
        os.write(self._to_chrome, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            answer = self._read(deadline)
            if answer.get("id") == self._id:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                return answer.get("result", {})

    def _read(self, deadline: float) -> dict[str, Any]:
        import select

        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("the browser did not answer")
            ready, _, _ = select.select([self._from_chrome], [], [], left)
            if ready:
                chunk = os.read(self._from_chrome, 1 << 20)
                if not chunk:
                    raise RuntimeError("the browser exited")
                self._buf += chunk
        line, self._buf = self._buf.split(b"\0", 1)
        result: dict[str, Any] = json.loads(line)
        return result

    def open(self, url: str) -> None:
        """Open ``url`` in a new page and attach to it."""
        target = self.send("Target.createTarget", {"url": url})["targetId"]
        self.session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"
        ]

    def screenshot(self) -> bytes:
        """The page as a PNG."""
        data = self.send("Page.captureScreenshot", {"format": "png"})["data"]
        return base64.b64decode(data)

    def close(self) -> None:
        """Close the browser (and kill it if it does not go)."""
        with contextlib.suppress(RuntimeError, TimeoutError, OSError):
            self.send("Browser.close", timeout=5.0)
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=10)
        for fd in (self._to_chrome, self._from_chrome):
            with contextlib.suppress(OSError):
                os.close(fd)


def _pipes(read_end: int, write_end: int) -> Callable[[], None]:
    def setup() -> None:  # in the child: chromium reads fd 3 and writes fd 4
        os.dup2(read_end, 3)
        os.dup2(write_end, 4)
        os.nice(10)

    return setup


def screenshots(
    exe: str,
    url: str,
    out: Path,
    ok: Callable[[Any], bool],
    *,
    profile: Path,
    timeout: float = 90.0,
    every: float = 3.0,
) -> Any:
    """Open ``url``; every ``every`` s take a screenshot (saved to ``out``) until ``ok(image)``
    holds for it (a PIL image) or ``timeout`` passes; the last image."""
    from PIL import Image

    browser = Browser(exe, profile)
    try:
        browser.open(url)
        deadline = time.monotonic() + timeout
        while True:
            time.sleep(every)
            png = browser.screenshot()
            out.write_bytes(png)
            image = Image.open(io.BytesIO(png)).convert("RGB")
            if ok(image) or time.monotonic() > deadline:
                return image
    finally:
        browser.close()


def count_near(image: Any, colour: tuple[int, int, int], tolerance: int = 40) -> int:
    """Pixels of ``image`` within ``tolerance`` of ``colour`` in every channel."""
    import numpy as np

    px = np.asarray(image, dtype=np.int16)
    near = (np.abs(px - np.array(colour, dtype=np.int16)) <= tolerance).all(axis=2)
    return int(near.sum())


def distinct_pixels(image: Any) -> int:
    """Pixels that differ from the image's most common colour (its background)."""
    import numpy as np

    px = np.asarray(image).reshape(-1, 3)
    colours, counts = np.unique(px, axis=0, return_counts=True)
    background = colours[counts.argmax()]
    return int((px != background).any(axis=1).sum())


async def replay_in_browser(
    cluster: Any, browser: str, recording: Path, png: Path, done: Callable[[Any], bool]
) -> tuple[Any, Any]:
    """``mover replay RECORDING`` started in ``cluster`` (a :func:`mover.testing.cluster`) and
    its page screenshotted into ``png`` until ``done(image)``: the replay's process and the
    last image."""
    from mover._config import free_port

    from .test_view_cli import expect_line

    port = free_port()
    replay = await cluster.start(
        "mover._cli", "replay", str(recording), "--port", str(port), ready=None
    )
    url = (await expect_line(replay, "mover replay: open", 60)).split()[-1]
    image = await asyncio.to_thread(
        screenshots, browser, url, png, done, profile=png.with_name(png.stem + "-chromium")
    )
    return replay, image


def browser_or_skip() -> str:
    """The browser to drive; the test skipped, saying why, without one."""
    import pytest

    browser = find_browser()
    if browser is None:
        pytest.skip("no Chromium on PATH (Debian: apt-get install chromium)")
    return browser


def shown(image: Any, colours: dict[str, tuple[int, int, int]]) -> dict[str, int]:
    """Pixels of each robot's colour in ``image`` (a robot is shown from :data:`ENOUGH`)."""
    return {name: count_near(image, rgb) for name, rgb in colours.items()}


def all_shown(colours: dict[str, tuple[int, int, int]]) -> Callable[[Any], bool]:
    """A screenshot's test: every robot of ``colours`` is shown."""
    return lambda image: min(shown(image, colours).values()) >= ENOUGH
