#!/usr/bin/env python3
"""Open a drape report's index.html in headless Chromium, as a person would, and say what it saw.

usage: report_browser.py INDEX_HTML SHOT_PNG

Prints one JSON object: console errors and uncaught exceptions, requests to anything but local
files, the page's height, the pictures and whether they loaded, what the 3D view drew and what
it shows under the canvas centre, and pixel statistics of screenshots of the 3D view before and
after a drag (saved to SHOT_PNG and SHOT_PNG with "-rotated"). Exit code 3: no Chromium.
The browser runs with every host name unresolvable, so nothing can be fetched from a network.
"""
import base64
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request

import numpy as np
import websocket
from PIL import Image

BROWSERS = ["chromium", "chromium-browser", "google-chrome"]


def find_browser():
    for b in BROWSERS:
        path = shutil.which(b)
        if path:
            return path
    return None


# How long a DevTools reply may take, seconds.
REPLY_TIMEOUT_S = 60


class Page:
    """A Chrome DevTools Protocol session with one page; events are collected as they come."""

    def __init__(self, ws_url):
        self.ws = websocket.create_connection(ws_url, timeout=REPLY_TIMEOUT_S, suppress_origin=True)
        self.next_id = 0
        self.events = []

    def send(self, method, **params):
        self.next_id += 1
        my_id = self.next_id
        # wait_for and drain leave the socket with the few milliseconds they had left: a reply
        # gets the whole minute again (a busy machine took longer to answer an evaluate).
        self.ws.settimeout(REPLY_TIMEOUT_S)
        self.ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_for(self, method, timeout):
        end = time.time() + timeout
        while time.time() < end:
            if any(e.get("method") == method for e in self.events):
                return True
            self.ws.settimeout(max(0.1, end - time.time()))
            try:
                self.events.append(json.loads(self.ws.recv()))
            except websocket.WebSocketTimeoutException:
                break
        return any(e.get("method") == method for e in self.events)

    def drain(self, seconds):
        end = time.time() + seconds
        while time.time() < end:
            self.ws.settimeout(max(0.05, end - time.time()))
            try:
                self.events.append(json.loads(self.ws.recv()))
            except websocket.WebSocketTimeoutException:
                break

    def evaluate(self, expr):
        r = self.send("Runtime.evaluate", expression=expr, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expr}: {r['exceptionDetails']}")
        return r["result"].get("value")


def pixel_stats(png_bytes):
    img = np.asarray(Image.open(io.BytesIO(png_bytes)).convert("RGB")).astype(int)
    background = np.all(img >= 250, axis=2)
    part = ~background
    colours = len({tuple(c) for c in img[part][::7]})
    return {
        "width": int(img.shape[1]),
        "height": int(img.shape[0]),
        "part_share": float(part.mean()),
        "distinct_colours": colours,
        "mean": [float(x) for x in img.reshape(-1, 3).mean(axis=0)],
    }


def main():
    index, shot = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    browser = find_browser()
    if browser is None:
        print(json.dumps({"error": "no chromium: install it with tools/run-tests (apt-get install chromium)"}))
        return 3
    profile = tempfile.mkdtemp(prefix="drape-chromium-")
    proc = subprocess.Popen(
        [
            browser,
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-extensions",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--host-resolver-rules=MAP * ~NOTFOUND",
            "--remote-debugging-port=0",
            f"--user-data-dir={profile}",
            "--window-size=1280,1000",
            "about:blank",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        port_file = os.path.join(profile, "DevToolsActivePort")
        for _ in range(300):
            if os.path.exists(port_file) and open(port_file).read().strip():
                break
            time.sleep(0.1)
        port = int(open(port_file).read().split()[0])
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=30))
        target = next(t for t in targets if t.get("type") == "page")
        page = Page(target["webSocketDebuggerUrl"])
        for domain in ["Page", "Runtime", "Log", "Network"]:
            page.send(f"{domain}.enable")
        page.send("Emulation.setDeviceMetricsOverride", width=1280, height=1000, deviceScaleFactor=1, mobile=False)
        page.send("Page.navigate", url="file://" + index)
        loaded = page.wait_for("Page.loadEventFired", 60)
        page.drain(1.0)
        facts = page.evaluate(
            """(() => {
              const c = document.getElementById('drape-view');
              c && c.scrollIntoView();
              const r = c ? c.getBoundingClientRect() : null;
              const v = window.drapeViewer;
              return {
                height: document.documentElement.scrollHeight,
                images: [...document.images].map(i => ({src: i.getAttribute('src'), loaded: i.complete && i.naturalWidth > 0, width: i.getBoundingClientRect().width})),
                canvas: r ? {x: r.x + window.scrollX, y: r.y + window.scrollY, width: r.width, height: r.height} : null,
                faces: v ? v.faces : null,
                plies: v ? v.plies : null,
                pick: v && c ? v.pick(c.width / 2, c.height / 2) : null,
              };
            })()"""
        )
        shots = {}
        if facts["canvas"]:
            c = facts["canvas"]
            clip = {"x": c["x"], "y": c["y"], "width": c["width"], "height": c["height"], "scale": 1}

            def capture(path):
                r = page.send("Page.captureScreenshot", format="png", clip=clip, captureBeyondViewport=True)
                data = base64.b64decode(r["data"])
                with open(path, "wb") as f:
                    f.write(data)
                return pixel_stats(data)

            shots["initial"] = capture(shot)
            # Drag across the view: it must turn the part.
            view = page.evaluate("(() => { const r = document.getElementById('drape-view').getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })()")
            x0, y0 = view[0] + view[2] / 2, view[1] + view[3] / 2
            page.send("Input.dispatchMouseEvent", type="mousePressed", x=x0, y=y0, button="left", clickCount=1)
            for k in range(1, 11):
                page.send("Input.dispatchMouseEvent", type="mouseMoved", x=x0 + 12 * k, y=y0 + 4 * k, button="left", buttons=1)
            page.send("Input.dispatchMouseEvent", type="mouseReleased", x=x0 + 120, y=y0 + 40, button="left", clickCount=1)
            page.drain(0.3)
            rotated = shot[:-4] + "-rotated.png"
            shots["rotated"] = capture(rotated)
            a = np.asarray(Image.open(shot).convert("RGB")).astype(int)
            b = np.asarray(Image.open(rotated).convert("RGB")).astype(int)
            shots["changed_share"] = float(np.any(a != b, axis=2).mean()) if a.shape == b.shape else 1.0
            # Colour by thickness: the view redraws without errors.
            facts["faces_by_thickness"] = page.evaluate(
                "(() => { const s = document.getElementById('drape-colour'); s.value = 'thickness'; s.dispatchEvent(new Event('change')); return window.drapeViewer.faces; })()"
            )
        page.drain(0.5)
        errors, external = [], []
        for e in page.events:
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert", "warning"):
                errors.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
            elif m == "Runtime.exceptionThrown":
                d = p.get("exceptionDetails", {})
                errors.append(d.get("exception", {}).get("description") or d.get("text", "exception"))
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                errors.append(p["entry"].get("text", ""))
            elif m == "Network.requestWillBeSent":
                url = p.get("request", {}).get("url", "")
                if not url.split(":", 1)[0] in ("file", "data", "about", "blob"):
                    external.append(url)
        print(json.dumps({"loaded": loaded, "errors": errors, "external_requests": external, **facts, "shots": shots}))
        return 0
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
