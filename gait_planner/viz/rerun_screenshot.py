"""A picture of a recording as a person sees it: rerun's web viewer in headless Chromium.

`screenshot_rrd` serves an .rrd with the web viewer of the `rerun` CLI (rerun-sdk 0.41:
``rerun --web-viewer``, gRPC and HTTP bound to 127.0.0.1 on free ports) and has headless
Chromium (Debian's ``chromium``) load it and save a PNG. Chromium draws WebGL with its
software rasteriser (SwiftShader), so no GPU or display is needed; it may reach nothing
but loopback (every other host name resolves to nothing, no proxy). Both processes are
bounded in time and stopped when done.
"""

from __future__ import annotations

import base64
import fcntl
import io
import json
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Sequence

__all__ = ["chromium", "rerun_cli", "screenshot_rrd", "ScreenshotError"]

_BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


class ScreenshotError(RuntimeError):
    """The viewer or the browser did not produce a picture."""


def chromium() -> str | None:
    """Path of a Chromium (or Chrome) executable, or None."""
    for name in _BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    return None


def rerun_cli() -> str | None:
    """Path of the `rerun` CLI of this interpreter's rerun-sdk (else on PATH), or None."""
    beside = Path(sys.executable).with_name("rerun")
    return str(beside) if beside.is_file() else shutil.which("rerun")


def _stop(process: subprocess.Popen) -> None:
    """End `process` and its process group (it was started in a session of its own)."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(process.pid, sig)
        except ProcessLookupError:
            break
        end = time.monotonic() + 5.0
        while time.monotonic() < end:
            process.poll()
            try:
                os.killpg(process.pid, 0)
            except ProcessLookupError:
                return
            time.sleep(0.05)
    process.poll()


def _viewer_url(viewer: subprocess.Popen, timeout: float) -> str:
    """The URL the viewer prints on stderr ("connect at http://127.0.0.1:P?url=...")."""
    lines: queue.Queue[str | None] = queue.Queue()

    def read() -> None:
        for line in viewer.stderr:  # type: ignore[union-attr]
            lines.put(line)
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()
    seen = []
    while True:
        try:
            line = lines.get(timeout=timeout)
        except queue.Empty:
            raise ScreenshotError(f"the rerun web viewer printed no URL in {timeout} s: "
                                  + "".join(seen)[-2000:]) from None
        if line is None:
            raise ScreenshotError("the rerun web viewer stopped: " + "".join(seen)[-2000:])
        seen.append(line)
        match = re.search(r"connect at (http://127\.0\.0\.1:\d+\S*)", line)
        if match:  # the gRPC URL names localhost; keep to the address it is bound to
            return match.group(1).replace("localhost", "127.0.0.1")


class _DevTools:
    """Chromium's DevTools protocol over ``--remote-debugging-pipe`` (fd 3 in, fd 4 out;
    messages are JSON texts ended by a NUL byte)."""

    def __init__(self, args: list[str]):
        low_in, self._write = os.pipe()
        self._read, low_out = os.pipe()
        # the child's ends on fds >= 10: putting them on 3 and 4 overwrites neither
        to_child, from_child = (fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (low_in, low_out))
        os.close(low_in)
        os.close(low_out)
        keep = (to_child, from_child)
        # a bare Python puts the pipe ends on fds 3 and 4, then becomes chromium
        relay = ("import os, sys; os.dup2(int(sys.argv[1]), 3); os.dup2(int(sys.argv[2]), 4); "
                 "os.closerange(5, 256); os.execv(sys.argv[3], sys.argv[3:])")
        self.process = subprocess.Popen(
            [sys.executable, "-I", "-S", "-c", relay, str(to_child), str(from_child), *args,
             "--remote-debugging-pipe"], pass_fds=keep,
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True)
        for fd in keep:
            os.close(fd)
        self._messages: queue.Queue[dict | None] = queue.Queue()
        self._next_id = 0
        threading.Thread(target=self._reader, daemon=True).start()

    def _reader(self) -> None:
        buffer = b""
        with os.fdopen(self._read, "rb", buffering=0) as pipe:
            while chunk := pipe.read(1 << 16):
                buffer += chunk
                *messages, buffer = buffer.split(b"\0")
                for message in messages:
                    self._messages.put(json.loads(message))
        self._messages.put(None)

    def call(self, method: str, timeout: float, session: str | None = None, **params) -> dict:
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params}
        if session:
            message["sessionId"] = session
        os.write(self._write, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            try:
                reply = self._messages.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise ScreenshotError(f"chromium did not answer {method} in {timeout} s") from None
            if reply is None:
                raise ScreenshotError(f"chromium stopped before answering {method}")
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise ScreenshotError(f"chromium: {method}: {reply['error']}")
                return reply.get("result", {})

    def close(self) -> None:
        try:
            os.close(self._write)
        except OSError:
            pass
        _stop(self.process)


def _distinct_colours(png: bytes) -> int:
    """How many distinct colours a PNG has (Pillow, pinned with matplotlib)."""
    from PIL import Image

    with Image.open(io.BytesIO(png)) as image:
        return len(image.convert("RGB").getcolors(1 << 24) or ())


def screenshot_rrd(rrd: str | os.PathLike, png: str | os.PathLike, *, width: int = 1600,
                   height: int = 1000, gestures: Sequence[Sequence[tuple[int, int]]] = (),
                   settle: float = 3.0, timeout: float = 120.0) -> Path:
    """Render `rrd` in rerun's web viewer in headless Chromium and save the page as `png`.

    Pictures are taken once a second; the one saved is the first that has not changed for
    `settle` seconds once the viewer shows more than a loading screen (more than 200
    colours). Raises ScreenshotError when Chromium or the rerun CLI is missing, or the
    page does not settle within `timeout` seconds.
    """
    browser, cli = chromium(), rerun_cli()
    if browser is None or cli is None:
        raise ScreenshotError(f"needs chromium ({browser}) and the rerun CLI ({cli})")
    png = Path(png).resolve()
    deadline = time.monotonic() + timeout
    env = dict(os.environ, BROWSER="true")  # the viewer must not open a browser itself
    viewer = subprocess.Popen(
        [cli, "--web-viewer", "--bind", "127.0.0.1", "--port", "0", "--web-viewer-port", "0",
         "--hide-welcome-screen", str(Path(rrd).resolve())],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        env=env, start_new_session=True)
    try:
        url = _viewer_url(viewer, timeout=min(30.0, timeout))
        with tempfile.TemporaryDirectory(prefix="gait_planner_chromium_",
                                         ignore_cleanup_errors=True) as profile:
            args = [browser, "--headless", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                    "--no-first-run", "--no-default-browser-check", "--hide-scrollbars",
                    "--no-proxy-server", "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
                    f"--user-data-dir={profile}", f"--window-size={width},{height}"]
            if hasattr(os, "geteuid") and os.geteuid() == 0:
                args.append("--no-sandbox")  # Chromium refuses to run as root otherwise
            devtools = _DevTools(args)
            try:
                shot = _settled_picture(devtools, url, width, height, gestures, settle, deadline)
            finally:
                devtools.close()
    finally:
        _stop(viewer)
    png.write_bytes(shot)
    return png


def _settled_picture(devtools: _DevTools, url: str, width: int, height: int,
                     gestures: Sequence[Sequence[tuple[int, int]]], settle: float,
                     deadline: float) -> bytes:
    target = devtools.call("Target.createTarget", 30.0, url=url)["targetId"]
    session = devtools.call("Target.attachToTarget", 30.0, targetId=target,
                            flatten=True)["sessionId"]
    devtools.call("Emulation.setDeviceMetricsOverride", 30.0, session, width=width,
                  height=height, deviceScaleFactor=1, mobile=False)
    shot = _settle(devtools, session, settle, deadline)
    for path in gestures:  # press at the first point, move through the rest, release
        steps = [("mouseMoved", path[0]), ("mousePressed", path[0])]
        steps += [("mouseMoved", point) for point in path[1:]] + [("mouseReleased", path[-1])]
        for kind, (x, y) in steps:
            devtools.call("Input.dispatchMouseEvent", 30.0, session, type=kind, x=x, y=y,
                          button="left", clickCount=1)
            time.sleep(0.2)
    if gestures:
        devtools.call("Input.dispatchMouseEvent", 30.0, session, type="mouseMoved", x=width - 1,
                      y=height // 2)  # no hover effects where the last gesture ended
        shot = _settle(devtools, session, settle, deadline)
    return shot


def _settle(devtools: _DevTools, session: str, settle: float, deadline: float) -> bytes:
    last, since = b"", time.monotonic()
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise ScreenshotError("the viewer did not settle in time")
        shot = base64.b64decode(devtools.call("Page.captureScreenshot", left, session,
                                              format="png")["data"])
        now = time.monotonic()
        if shot != last or _distinct_colours(shot) <= 200:
            last, since = shot, now
        elif now - since >= settle:
            return shot
        time.sleep(1.0)
