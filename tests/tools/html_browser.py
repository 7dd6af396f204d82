#!/usr/bin/env python3
"""Drives the page of `loopfarm report DB --html FILE` in headless Chromium.

    html_browser.py CHROMIUM PAGE.html [SCREENSHOT.png]

Speaks the DevTools protocol over --remote-debugging-pipe (file descriptors
3 and 4, messages ended by a NUL byte), with nothing but the standard library.
Loads the page and checks, in order:

  1. it loads with no console error, no uncaught exception and no failed
     request, and the first viewer's canvas is drawn (not blank);
  2. the canvas stays the same while nothing happens (it does not play by itself);
  3. a mouse click on the first viewer's slider changes the input angle, and
     the canvas differs from before;
  4. a mouse drag across the canvas turns the view: the canvas differs again;
  5. Play moves the linkage (the canvas changes by itself), Pause stops it;
  6. no console error was logged meanwhile.

Exit 0 on success; on failure one line saying what went wrong, and exit 1.
"""
import base64
import json
import os
import select
import subprocess
import sys
import tempfile
import time

TIMEOUT = 30.0  # seconds for any one answer of the browser


def fail(message):
    print("html_browser: FAILED: " + " ".join(message.split()), file=sys.stderr)
    sys.exit(1)


class Browser:
    def __init__(self, chromium, profile):
        # The browser reads commands from its fd 3 and writes answers to its fd 4.
        self.log = tempfile.TemporaryFile()  # the browser's stderr, quoted when it dies
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()
        remap = "exec 3<&%d 4>&%d; exec \"$@\"" % (to_browser_r, from_browser_w)
        self.process = subprocess.Popen(
            ["sh", "-c", remap, "sh", chromium, "--headless", "--no-sandbox", "--disable-gpu",
             "--disable-dev-shm-usage", "--remote-debugging-pipe", "--user-data-dir=" + profile, "--no-first-run",
             "--no-default-browser-check", "--disable-extensions", "--window-size=1280,1000",
             "--force-device-scale-factor=1", "about:blank"],
            pass_fds=(to_browser_r, from_browser_w),
            stdout=subprocess.DEVNULL, stderr=self.log)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []

    def send(self, method, params=None, session=None):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        return self.wait(lambda m: m.get("id") == self.next_id, method)

    def read_message(self, deadline):
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            ready, _, _ = select.select([self.from_browser], [], [], left)
            if not ready:
                return None
            chunk = os.read(self.from_browser, 1 << 20)
            if not chunk:
                self.log.seek(0)
                last = [line for line in self.log.read().decode(errors="replace").splitlines() if line.strip()]
                fail("the browser closed its pipe (exit code %s): %s" % (self.process.poll(), " | ".join(last[-3:])))
            self.buffer += chunk
        raw, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(raw)

    def wait(self, predicate, what):
        """The first message that satisfies `predicate`; events on the way are kept."""
        for i, event in enumerate(self.events):
            if predicate(event):
                return self.events.pop(i)
        deadline = time.monotonic() + TIMEOUT
        while True:
            message = self.read_message(deadline)
            if message is None:
                fail("no answer from the browser to %s in %.0f s" % (what, TIMEOUT))
            if predicate(message):
                if "error" in message:
                    fail("%s: %s" % (what, message["error"]))
                return message
            self.events.append(message)

    def drain(self, seconds):
        deadline = time.monotonic() + seconds
        while True:
            message = self.read_message(deadline)
            if message is None:
                return
            self.events.append(message)

    def close(self):
        """Asks the browser to quit, and waits until it has (its profile is then free to remove)."""
        try:
            message = {"id": self.next_id + 1, "method": "Browser.close", "params": {}}
            os.write(self.to_browser, json.dumps(message).encode() + b"\0")
            self.process.wait(timeout=10)
        except Exception:
            self.process.kill()
            self.process.wait()


def problems(events):
    """Console errors, uncaught exceptions and failed loads among the events."""
    found = []
    for e in events:
        method, params = e.get("method"), e.get("params", {})
        if method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            found.append("uncaught exception: %s %s" % (
                details.get("text", ""), details.get("exception", {}).get("description", "")))
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            found.append("console.%s: %s" % (params["type"], " ".join(
                str(a.get("value", a.get("description", ""))) for a in params.get("args", []))))
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            found.append("log error: %s" % params["entry"].get("text", ""))
        elif method == "Network.loadingFailed":
            found.append("failed request: %s" % params.get("errorText", ""))
        elif method == "Network.requestWillBeSent":
            url = params.get("request", {}).get("url", "")
            if not url.startswith(("file:", "data:", "about:")):
                found.append("request to %s" % url)
    return found


def main():
    if len(sys.argv) not in (3, 4):
        fail("usage: html_browser.py CHROMIUM PAGE.html [SCREENSHOT.png]")
    chromium, page = sys.argv[1], os.path.abspath(sys.argv[2])
    if not os.access(chromium, os.X_OK):
        fail("no browser at %s (scripts/deps.sh --test installs chromium)" % chromium)
    # The browser's helper processes may still be leaving the profile when it
    # exits; what they leave behind is removed as well as can be.
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        browser = Browser(chromium, profile)
        try:
            run(browser, page, sys.argv[3] if len(sys.argv) == 4 else None)
        finally:
            browser.close()


def run(browser, page, screenshot):
    target = browser.send("Target.createTarget", {"url": "about:blank"})["result"]["targetId"]
    session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["result"]["sessionId"]

    def call(method, params=None):
        return browser.send(method, params, session).get("result", {})

    def evaluate(expression):
        result = call("Runtime.evaluate", {"expression": expression, "returnByValue": True})
        if "exceptionDetails" in result:
            fail("evaluating %s: %s" % (expression, result["exceptionDetails"].get("text")))
        return result["result"].get("value")

    for domain in ("Page", "Runtime", "Log", "Network"):
        call(domain + ".enable")
    call("Page.navigate", {"url": "file://" + page})
    browser.wait(lambda m: m.get("method") == "Page.loadEventFired" and m.get("sessionId") == session,
                 "Page.loadEventFired")
    browser.drain(0.5)
    found = problems(browser.events)
    if found:
        fail("loading the page: " + "; ".join(found))

    viewers = evaluate("document.querySelectorAll('.viewer canvas').length")
    if not viewers:
        fail("the page has no 3D view")
    canvas = "document.querySelector('.viewer canvas')"
    blank = evaluate("(() => { const c = document.createElement('canvas'); const s = %s;"
                     " c.width = s.width; c.height = s.height; const x = c.getContext('2d');"
                     " x.fillStyle = '#fff'; x.fillRect(0, 0, c.width, c.height); return c.toDataURL(); })()"
                     % canvas)
    pixels = lambda: evaluate(canvas + ".toDataURL()")
    first = pixels()
    if first == blank:
        fail("the 3D view is blank after loading")
    time.sleep(0.3)
    if pixels() != first:
        fail("the 3D view changes while nothing happens (it should start paused)")

    def box(selector):
        return evaluate("(() => { const e = document.querySelector(%s); e.scrollIntoView({block: 'center'});"
                        " const r = e.getBoundingClientRect();"
                        " return [r.left, r.top, r.width, r.height]; })()" % json.dumps(selector))

    def mouse(kind, x, y, buttons):
        call("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left",
                                           "buttons": buttons, "clickCount": 1 if kind != "mouseMoved" else 0})

    # The slider: a click at three quarters of its track.
    slider = ".viewer input[type=range]"
    before = evaluate("document.querySelector(%s).value" % json.dumps(slider))
    left, top, width, height = box(slider)
    x, y = left + 0.75 * width, top + height / 2
    mouse("mousePressed", x, y, 1)
    mouse("mouseReleased", x, y, 0)
    after = evaluate("document.querySelector(%s).value" % json.dumps(slider))
    if after == before:
        fail("a click on the slider did not change its value (%s)" % before)
    moved = pixels()
    if moved == first:
        fail("the 3D view did not change when the slider moved from %s to %s" % (before, after))

    # The view: a drag across the canvas, in steps.
    left, top, width, height = box(".viewer canvas")
    x0, y0 = left + width / 2, top + height / 2
    mouse("mouseMoved", x0, y0, 0)
    mouse("mousePressed", x0, y0, 1)
    for k in range(1, 11):
        mouse("mouseMoved", x0 + 12 * k, y0 + 5 * k, 1)
    mouse("mouseReleased", x0 + 120, y0 + 50, 0)
    turned = pixels()
    if turned == moved:
        fail("the 3D view did not change when dragged")

    # Play moves the linkage by itself; Pause stops it.
    def click(selector):
        left, top, width, height = box(selector)
        mouse("mousePressed", left + width / 2, top + height / 2, 1)
        mouse("mouseReleased", left + width / 2, top + height / 2, 0)

    click(".viewer button.play")
    time.sleep(0.4)
    playing = pixels()
    if playing == turned:
        fail("the 3D view did not change while playing")
    click(".viewer button.play")
    paused = pixels()
    time.sleep(0.3)
    if pixels() != paused:
        fail("the 3D view still changes after Pause")

    browser.drain(0.2)
    found = problems(browser.events)
    if found:
        fail("using the page: " + "; ".join(found))
    if screenshot:
        shot = call("Page.captureScreenshot", {"format": "png"})
        with open(screenshot, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
    print("html_browser: ok (%d 3D views; slider %s -> %s deg; drag turned the view; play and pause)"
          % (viewers, before, after))


if __name__ == "__main__":
    main()
