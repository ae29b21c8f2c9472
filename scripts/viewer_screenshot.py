#!/usr/bin/env python3
"""Screenshot a quadwalk recording in Rerun's web viewer, as a person sees it.

    python scripts/viewer_screenshot.py RECORDING.rrd OUT.png

Serves RECORDING with the `rerun` command of rerun-sdk 0.36.3 (the one
beside this Python, else on PATH), opens Rerun's web viewer in headless
Chromium (Debian's `chromium`; WebGL through its software rasteriser:
`--use-angle=swiftshader --enable-unsafe-swiftshader`, viewer URL
`renderer=webgl`), waits until the viewer has drawn the recording (5 s
after the robot's colour first shows, two screenshots 3 s apart alike),
and saves the screenshot to OUT.

Then it checks that the robot is in the 3D view: it makes a copy of the
recording without the robot's shapes (`rerun rrd filter --drop-entity`),
screenshots that the same way, and counts the pixels that differ between
the two and have the robot's colour (quadwalk draws the links in
(200, 160, 60), shaded). The check passes when they cover at least
--min-robot-percent of the screenshot; the counts are printed and written
beside OUT as JSON. Exit status 0 when it passes, 1 when the robot is not
in view, 2 on bad input or a tool that is missing or fails.

Needs: Python 3.9+ with Pillow and NumPy (rerun-sdk installs both) and
Chromium. The
Chrome DevTools protocol is spoken over a plain WebSocket written here, so
nothing else is installed.
"""

from __future__ import annotations

import argparse
import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.parse
import urllib.request
from pathlib import Path

# The robot's link colour in quadwalk's recordings (viz crate).
ROBOT_RGB = (200, 160, 60)


class Failure(Exception):
    """Bad input, or a tool that is missing or fails (exit status 2)."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_http(url: str, timeout_s: float, what: str) -> bytes:
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url, timeout=5) as response:
                return response.read()
        except OSError as e:
            last = e
            time.sleep(0.5)
    raise Failure(f"{what} did not answer at {url} within {timeout_s:.0f} s ({last})")


class DevTools:
    """A minimal Chrome DevTools protocol client over a WebSocket."""

    def __init__(self, ws_url: str):
        parts = urllib.parse.urlparse(ws_url)
        self.sock = socket.create_connection((parts.hostname, parts.port), timeout=120)
        key = base64.b64encode(os.urandom(16)).decode()
        request = (
            f"GET {parts.path} HTTP/1.1\r\nHost: {parts.hostname}:{parts.port}\r\n"
            "Upgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        )
        self.sock.sendall(request.encode())
        response = b""
        while b"\r\n\r\n" not in response:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise Failure("Chromium closed the DevTools connection during the handshake")
            response += chunk
        if b" 101 " not in response.split(b"\r\n", 1)[0]:
            raise Failure(f"DevTools handshake refused: {response[:200]!r}")
        self.buffer = response.split(b"\r\n\r\n", 1)[1]
        self.next_id = 0

    def _recv_exact(self, n: int) -> bytes:
        while len(self.buffer) < n:
            chunk = self.sock.recv(1 << 20)
            if not chunk:
                raise Failure("Chromium closed the DevTools connection")
            self.buffer += chunk
        data, self.buffer = self.buffer[:n], self.buffer[n:]
        return data

    def _send_text(self, text: str) -> None:
        payload = text.encode()
        header = bytes([0x81])
        n = len(payload)
        if n < 126:
            header += bytes([0x80 | n])
        elif n < 1 << 16:
            header += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            header += bytes([0x80 | 127]) + struct.pack(">Q", n)
        mask = os.urandom(4)
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
        self.sock.sendall(header + mask + masked)

    def _recv_message(self) -> str:
        message = b""
        while True:
            first, second = self._recv_exact(2)
            n = second & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._recv_exact(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._recv_exact(8))[0]
            if second & 0x80:
                mask = self._recv_exact(4)
                data = bytes(b ^ mask[i % 4] for i, b in enumerate(self._recv_exact(n)))
            else:
                data = self._recv_exact(n)
            opcode = first & 0x0F
            if opcode == 0x8:
                raise Failure("Chromium closed the DevTools connection")
            if opcode in (0x9, 0xA):  # ping, pong
                continue
            message += data
            if first & 0x80:
                return message.decode()

    def call(self, method: str, **params) -> dict:
        self.next_id += 1
        call_id = self.next_id
        self._send_text(json.dumps({"id": call_id, "method": method, "params": params}))
        while True:
            reply = json.loads(self._recv_message())
            if reply.get("id") == call_id:
                if "error" in reply:
                    raise Failure(f"DevTools {method}: {reply['error']}")
                return reply.get("result", {})


def robot_pixel_mask(image):
    """Pixels of the robot's hue (amber, shaded), as a boolean array."""
    import numpy as np

    rgb = np.asarray(image.convert("RGB")).astype(np.float32)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    # (200, 160, 60) shaded keeps r > g > b with g/r about 0.8 and b well
    # below both; the tiles (grey to red), the grid and the panels do not.
    ratio = g / np.maximum(r, 1.0)
    return (r >= 60) & (r > g) & (g > b) & (ratio >= 0.6) & (ratio <= 0.92) & (r - b >= 0.5 * r)


def screenshot(
    recording: Path,
    out: Path,
    rerun: str,
    chromium: str,
    size: tuple[int, int],
    timeout_s: float,
    log_dir: Path,
    shown_after_s: float | None = None,
) -> float:
    """Serves `recording`, opens it in headless Chromium and saves a
    screenshot once the viewer has drawn it: 5 s after the data shows, when
    two screenshots 3 s apart are alike. The data shows when the robot's
    colour first does, or, for a recording without the robot, after
    `shown_after_s` (what it took the recording with the robot). Returns
    the seconds the data took to show."""
    from PIL import Image, ImageChops

    web_port, grpc_port, devtools_port = free_port(), free_port(), free_port()
    server_log = open(log_dir / f"{out.stem}-rerun.log", "w")
    server = subprocess.Popen(
        [
            rerun,
            "--serve-web",
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            str(recording),
        ],
        stdout=server_log,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    browser = None
    try:
        wait_for_http(f"http://127.0.0.1:{web_port}/", 60, "rerun --serve-web")
        viewer_url = (
            f"http://127.0.0.1:{web_port}/?url="
            + urllib.parse.quote(f"rerun+http://127.0.0.1:{grpc_port}/proxy", safe="")
            + "&renderer=webgl"
        )
        profile = tempfile.mkdtemp(prefix=f"{out.stem}-chromium-profile-", dir=log_dir)
        browser_log = open(log_dir / f"{out.stem}-chromium.log", "w")
        browser = subprocess.Popen(
            [
                chromium,
                "--headless=new",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--ignore-gpu-blocklist",
                "--hide-scrollbars",
                f"--window-size={size[0]},{size[1]}",
                f"--remote-debugging-port={devtools_port}",
                f"--user-data-dir={profile}",
                viewer_url,
            ],
            stdout=browser_log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        page = None
        waited = time.monotonic() + 60
        while page is None:
            targets = json.loads(
                wait_for_http(f"http://127.0.0.1:{devtools_port}/json", 60, "Chromium's DevTools")
            )
            page = next(
                (t for t in targets if t.get("type") == "page" and t.get("url", "").startswith(f"http://127.0.0.1:{web_port}")),
                None,
            )
            if page is None:
                if time.monotonic() > waited:
                    raise Failure(f"Chromium did not open {viewer_url}")
                time.sleep(1)
        tools = DevTools(page["webSocketDebuggerUrl"])
        opened = time.monotonic()
        previous = None
        while True:
            shot = base64.b64decode(tools.call("Page.captureScreenshot", format="png")["data"])
            out.write_bytes(shot)
            image = Image.open(out).convert("RGB")
            now = time.monotonic()
            if shown_after_s is None and robot_pixel_mask(image).any():
                shown_after_s = now - opened
            ready = shown_after_s is not None and now - opened > shown_after_s + 5
            if (
                ready
                and previous is not None
                and ImageChops.difference(image, previous).getbbox() is None
            ):
                return shown_after_s
            if now - opened > timeout_s:
                raise Failure(
                    f"the viewer had not settled on {recording} after {timeout_s:.0f} s "
                    f"(last screenshot: {out})"
                )
            previous = image
            time.sleep(3)
    finally:
        for process in [browser, server]:
            if process is not None:
                stop(process)


def stop(process: subprocess.Popen) -> None:
    """Ends `process` and its children (its own process group: the `rerun`
    command is a Python wrapper around the binary that serves): SIGTERM,
    then SIGKILL after 10 s."""
    import signal

    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(process.pid, sig)
        except ProcessLookupError:
            return
        try:
            process.wait(timeout=10)
            # The group may outlive its leader: make sure of the rest.
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            return
        except subprocess.TimeoutExpired:
            continue
        return


def recording_without_robot(recording: Path, rerun: str, out: Path) -> None:
    """`recording` less the robot's shapes (the eye's anchor stays)."""
    printed = subprocess.run(
        [rerun, "rrd", "print", "--verbose", str(recording)], capture_output=True, text=True
    )
    if printed.returncode != 0:
        raise Failure(f"rerun rrd print {recording} failed: {printed.stderr.strip()[:500]}")
    shapes = sorted(
        {
            word.strip("'\",")
            for word in printed.stdout.split()
            if word.strip("'\",").lstrip("/").startswith("world/robot/")
            and "/shape_" in word
        }
    )
    if not shapes:
        raise Failure(
            f"{recording} has no robot shapes (world/robot/<link>/shape_<k>); is it a quadwalk recording?"
        )
    command = [rerun, "rrd", "filter", str(recording), "-o", str(out)]
    for path in shapes:
        command += ["--drop-entity", path]
    filtered = subprocess.run(command, capture_output=True, text=True)
    if filtered.returncode != 0:
        raise Failure(f"rerun rrd filter failed: {filtered.stderr.strip()[:500]}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("recording", type=Path, help="a quadwalk .rrd (--rerun save:FILE)")
    parser.add_argument("out", type=Path, help="the screenshot to write (.png)")
    parser.add_argument("--size", default="1600x900", help="window size WxH (default 1600x900)")
    parser.add_argument(
        "--timeout", type=float, default=240, help="seconds to wait for the viewer (default 240)"
    )
    parser.add_argument(
        "--min-robot-percent",
        type=float,
        default=0.5,
        help="robot pixels needed, percent of the screenshot (default 0.5)",
    )
    args = parser.parse_args()
    try:
        if not args.recording.is_file():
            raise Failure(f"recording {args.recording}: no such file")
        if args.out.suffix.lower() != ".png":
            raise Failure(f"out {args.out}: the screenshot is a PNG; name it .png")
        try:
            w, h = (int(v) for v in args.size.lower().split("x"))
            if not (320 <= w <= 4096 and 240 <= h <= 4096):
                raise ValueError
        except ValueError:
            raise Failure(f"--size {args.size}: expected WxH, 320..4096 x 240..4096") from None
        beside = Path(sys.executable).parent / "rerun"
        rerun = str(beside) if beside.exists() else shutil.which("rerun")
        if rerun is None:
            raise Failure("no `rerun` command: pip install rerun-sdk==0.36.3")
        chromium = shutil.which("chromium") or shutil.which("chromium-browser")
        if chromium is None:
            raise Failure("no `chromium`: apt-get install chromium")
        args.out.parent.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix="quadwalk-screenshot-"))
        without = work / "without-robot.rrd"
        recording_without_robot(args.recording, rerun, without)
        reference = work / "without-robot.png"
        shown_after_s = None
        for recording, out in [(args.recording, args.out), (without, reference)]:
            started = time.monotonic()
            shown_after_s = screenshot(
                recording, out, rerun, chromium, (w, h), args.timeout, work, shown_after_s
            )
            print(f"{out}: drawn in {time.monotonic() - started:.0f} s", file=sys.stderr)

        from PIL import Image, ImageChops

        with_robot = Image.open(args.out).convert("RGB")
        without_robot = Image.open(reference).convert("RGB")
        if with_robot.size != without_robot.size:
            raise Failure("the two screenshots differ in size")
        import numpy as np

        difference = np.asarray(ImageChops.difference(with_robot, without_robot))
        differ = difference.max(axis=2) > 24
        amber = robot_pixel_mask(with_robot)
        amber_reference = robot_pixel_mask(without_robot)
        robot = int((differ & amber).sum())
        total = with_robot.size[0] * with_robot.size[1]
        report = {
            "recording": str(args.recording),
            "screenshot": str(args.out),
            "size": list(with_robot.size),
            "pixels_differing_from_without_robot": int(differ.sum()),
            "robot_pixels": robot,
            "robot_percent": round(100.0 * robot / total, 3),
            "robot_coloured_pixels_without_robot": int(amber_reference.sum()),
            "min_robot_percent": args.min_robot_percent,
        }
        report["robot_in_view"] = report["robot_percent"] >= args.min_robot_percent
        args.out.with_suffix(".json").write_text(json.dumps(report, indent=2) + "\n")
        print(json.dumps(report, indent=2))
        shutil.rmtree(work, ignore_errors=True)
        return 0 if report["robot_in_view"] else 1
    except Failure as e:
        print(f"viewer_screenshot: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
