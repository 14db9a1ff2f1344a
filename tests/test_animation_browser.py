"""The exported animation plays in a real browser: headless Chromium, two screenshots.

Chromium (Debian package ``chromium``; CI installs it) opens the exported HTML
file with the network disabled and software WebGL (SwiftShader). The test
drives it through the DevTools protocol (a minimal WebSocket client below, no
extra dependency): it waits until the page has built the scene and started the
animation, takes a screenshot, waits 1.5 s, takes another, and checks

* no JavaScript exception or console error;
* the mechanism is drawn: enough coloured pixels (blue platform, orange
  pistons, red arrows; the background and floor grid are grey) in the middle of
  the view, in both screenshots;
* the animation plays: its clock advanced and the two screenshots differ
  outside the caption.

Skipped only if no Chromium executable is found.
"""

from __future__ import annotations

import base64
import io
import json
import os
import re
import shutil
import socket
import struct
import subprocess
import tempfile
import time
import urllib.parse
import urllib.request
from pathlib import Path

import sys

import numpy as np
import pytest

from robot.viz.animation import export_html

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_animation import write_result  # noqa: E402  (the synthetic results of the fast tests)

CHROMIUM = next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"), "/usr/bin/chromium") if p and Path(p).is_file()), None)
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="headless browser test needs Chromium (Debian package 'chromium'); not found on PATH")

WIDTH, HEIGHT = 800, 600
CAPTION_ROWS = 40  # the caption shows the simulated time: keep it out of the comparisons
TIMEOUT = 30.0


class DevTools:
    """Just enough of a WebSocket client (RFC 6455, text frames) to call the DevTools protocol."""

    def __init__(self, url: str):
        parts = urllib.parse.urlsplit(url)
        self.sock = socket.create_connection((parts.hostname, parts.port), timeout=TIMEOUT)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(
            (f"GET {parts.path} HTTP/1.1\r\nHost: {parts.hostname}:{parts.port}\r\nUpgrade: websocket\r\n"
             f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode()
        )
        self.buffer = b""
        while b"\r\n\r\n" not in self.buffer:
            self.buffer += self._chunk()
        header, self.buffer = self.buffer.split(b"\r\n\r\n", 1)
        assert b" 101 " in header.split(b"\r\n")[0], header
        self.last_id = 0
        self.events: list[dict] = []

    def _chunk(self) -> bytes:
        chunk = self.sock.recv(1 << 16)
        if not chunk:
            raise ConnectionError("DevTools connection closed")
        return chunk

    def _exact(self, n: int) -> bytes:
        while len(self.buffer) < n:
            self.buffer += self._chunk()
        data, self.buffer = self.buffer[:n], self.buffer[n:]
        return data

    def _send(self, opcode: int, payload: bytes) -> None:
        n = len(payload)
        header = bytes([0x80 | opcode])
        if n < 126:
            header += bytes([0x80 | n])
        elif n < 1 << 16:
            header += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            header += bytes([0x80 | 127]) + struct.pack(">Q", n)
        mask = os.urandom(4)
        masked = (np.frombuffer(payload, np.uint8) ^ np.resize(np.frombuffer(mask, np.uint8), n)).tobytes()
        self.sock.sendall(header + mask + masked)

    def _message(self) -> str:
        message = b""
        while True:
            first, second = self._exact(2)
            n = second & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._exact(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._exact(8))[0]
            mask = self._exact(4) if second & 0x80 else None
            payload = self._exact(n)
            if mask:
                payload = (np.frombuffer(payload, np.uint8) ^ np.resize(np.frombuffer(mask, np.uint8), n)).tobytes()
            opcode = first & 0x0F
            if opcode == 0x8:
                raise ConnectionError("DevTools connection closed by the browser")
            if opcode == 0x9:
                self._send(0xA, payload)
                continue
            message += payload
            if first & 0x80:
                return message.decode("utf-8")

    def call(self, method: str, **params) -> dict:
        self.last_id += 1
        self._send(0x1, json.dumps({"id": self.last_id, "method": method, "params": params}).encode())
        while True:
            reply = json.loads(self._message())
            if reply.get("id") == self.last_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self.events.append(reply)

    def evaluate(self, expression: str):
        reply = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        if "exceptionDetails" in reply:
            raise RuntimeError(f"{expression}: {reply['exceptionDetails']}")
        return reply["result"].get("value")

    def screenshot(self) -> bytes:
        return base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])

    def errors(self) -> list[str]:
        out = []
        for event in self.events:
            if event.get("method") == "Runtime.exceptionThrown":
                out.append(json.dumps(event["params"]["exceptionDetails"])[:500])
            elif event.get("method") == "Runtime.consoleAPICalled" and event["params"]["type"] == "error":
                out.append(json.dumps(event["params"]["args"])[:500])
        return out

    def close(self) -> None:
        self.sock.close()


def launch(profile: str) -> tuple[subprocess.Popen, str]:
    """Start headless Chromium on about:blank; return the process and the page's DevTools WebSocket URL."""
    process = subprocess.Popen(
        [
            CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
            "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--disable-extensions",
            "--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND",  # no network: the page must not need it
            f"--user-data-dir={profile}", f"--window-size={WIDTH},{HEIGHT}", "--remote-debugging-port=0", "about:blank",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + TIMEOUT
    log = []
    while time.monotonic() < deadline:
        line = process.stderr.readline()
        if not line and process.poll() is not None:
            break
        log.append(line)
        found = re.search(r"DevTools listening on ws://127\.0\.0\.1:(\d+)/", line)
        if found:
            port = found.group(1)
            for _ in range(100):
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as reply:
                    pages = [t for t in json.load(reply) if t["type"] == "page"]
                if pages:
                    return process, pages[0]["webSocketDebuggerUrl"]
                time.sleep(0.1)
    process.kill()
    process.wait()
    raise AssertionError("Chromium did not start its DevTools endpoint:\n" + "".join(log)[-3000:])


def rgb(png: bytes) -> np.ndarray:
    from PIL import Image

    with Image.open(io.BytesIO(png)) as image:
        return np.asarray(image.convert("RGB"), dtype=int)


def coloured(image: np.ndarray) -> np.ndarray:
    scene = image[CAPTION_ROWS:]
    return (scene.max(axis=2) - scene.min(axis=2)) > 60


@pytest.fixture(scope="module")
def page(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("browser")
    result = write_result(folder, ["S1", "R1"], duration=0.2, n=41)
    # 0.2 s simulated at speed 0.02: a 10 s animation, longer than the test looks at it
    summary = export_html(result, folder / "animation.html", exaggerate=100, speed=0.02)
    assert summary.n_frames == 301
    return summary.html_path


def test_animation_is_drawn_and_plays(page, tmp_path):
    # Chromium's helper processes can still write to the profile while it is removed: ignore that
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        process, url = launch(profile)
        try:
            tools = DevTools(url)
            tools.call("Runtime.enable")
            tools.call("Page.enable")
            tools.call("Emulation.setDeviceMetricsOverride", width=WIDTH, height=HEIGHT, deviceScaleFactor=1, mobile=False)
            tools.call("Page.navigate", url=page.as_uri())
            deadline = time.monotonic() + TIMEOUT
            while not tools.evaluate("window.meshcatReady === true && viewer.animator.actions.length > 0 && viewer.animator.playing"):
                assert time.monotonic() < deadline, "the page did not build the scene and start the animation"
                time.sleep(0.2)
            time.sleep(0.5)  # let a few frames render
            t1, first = tools.evaluate("viewer.animator.time"), tools.screenshot()
            time.sleep(1.5)
            t2, second = tools.evaluate("viewer.animator.time"), tools.screenshot()
            errors = tools.errors()
            tools.close()
        finally:
            process.kill()
            process.wait()
    images = {}
    for name, png in (("first", first), ("second", second)):
        (tmp_path / f"{name}.png").write_bytes(png)  # kept for inspection (pytest --basetemp=DIR)
        images[name] = image = rgb(png)
        assert image.shape == (HEIGHT, WIDTH, 3), image.shape
        mask = coloured(image)
        assert mask.mean() > 0.02, f"{name} screenshot: only {mask.mean():.3%} coloured pixels: the mechanism is not drawn"
        rows, cols = np.nonzero(mask)
        assert WIDTH * 0.3 < cols.mean() < WIDTH * 0.7 and HEIGHT * 0.1 < rows.mean() < HEIGHT * 0.75, "the mechanism is off-centre"
    assert errors == [], errors
    assert 0.0 <= t1 < t2 < 10.0, (t1, t2)
    changed = np.abs(images["first"][CAPTION_ROWS:] - images["second"][CAPTION_ROWS:]).max(axis=2) > 40
    assert changed.sum() > 100, f"only {changed.sum()} pixels changed in 1.5 s: the animation does not play"
