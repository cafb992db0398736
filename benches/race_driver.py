#!/usr/bin/env python3
"""Opens race files in headless Chromium through chromedriver (the WebDriver protocol,
plain HTTP) and measures each: frames a second while it plays at 200 steps a second,
the time to draw one frame stepping forward and jumping to any frame, and the script's
heap after a garbage collection (what the page keeps: its data and its canvases' state). Prints a Markdown table, the first file as the baseline.

    python3 benches/race_driver.py BASELINE.html RACE.html
"""
import json
import socket
import statistics
import subprocess
import sys
import time
import urllib.request

ROUNDS = 5


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def call(base, method, path, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method,
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=120) as r:
        return json.load(r)["value"]


MEASURE = """
const done = arguments[arguments.length - 1];
const box = document.querySelector('.fn-race');
const slider = document.querySelector('.fn-slider');
const last = Number(slider.max);
const go = f => { slider.value = String(f); slider.dispatchEvent(new Event('input')); };
const robots = document.querySelectorAll('.fn-legend li').length;
// Drawing one frame, stepping forward from the start.
go(0);
let t0 = performance.now();
for (let f = 1; f <= last; f++) go(f);
const forward = (performance.now() - t0) / last;
// Jumping to frames anywhere (the trails drawn again from their run's start).
let seed = 7;
const rand = () => (seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648;
t0 = performance.now();
const jumps = 100;
for (let i = 0; i < jumps; i++) go(Math.floor(rand() * last));
const jump = (performance.now() - t0) / jumps;
// Playing at 200 steps a second for 3 s: frames a second.
go(0);
document.querySelector('.fn-speed').value = '200';
document.querySelector('.fn-speed').dispatchEvent(new Event('change'));
let frames = 0;
const count = () => { frames++; if (performance.now() - start < 3000) requestAnimationFrame(count); };
const start = performance.now();
document.querySelector('.fn-play').click();
requestAnimationFrame(count);
setTimeout(() => {
  document.querySelector('.fn-play').click();
  if (window.gc) window.gc();
  const heap = performance.memory ? performance.memory.usedJSHeapSize : 0;
  done({robots, last, forward, jump, fps: frames / 3, step: Number(box.getAttribute('data-frame')), heap});
}, 3100);
"""


def measure(base, session, path):
    call(base, "POST", f"/session/{session}/url", {"url": "file://" + path})
    call(base, "POST", f"/session/{session}/timeouts", {"script": 60000})
    return call(base, "POST", f"/session/{session}/execute/async", {"script": MEASURE, "args": []})


def main():
    files = sys.argv[1:]
    port = free_port()
    driver = subprocess.Popen(["chromedriver", f"--port={port}"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(100):
            try:
                urllib.request.urlopen(base + "/status", timeout=1)
                break
            except OSError:
                time.sleep(0.1)
        caps = {"capabilities": {"alwaysMatch": {"goog:chromeOptions": {
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--window-size=1300,1100", "--enable-precise-memory-info",
                     "--js-flags=--expose-gc"]}}}}
        session = call(base, "POST", "/session", caps)["sessionId"]
        results = {f: [] for f in files}
        for _ in range(ROUNDS):
            for f in files:
                results[f].append(measure(base, session, f))
        call(base, "DELETE", f"/session/{session}")
    finally:
        driver.kill()
    print(f"| race file ({ROUNDS} rounds, in turn, medians) | robots | frames | "
          "frames a second playing at 200 steps/s | ms a frame, stepping forward | "
          "ms a frame, jumping anywhere | JS heap (MiB) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for i, f in enumerate(files):
        rs = results[f]
        med = lambda k: statistics.median(r[k] for r in rs)
        name = "the baseline: its longest-running robot alone" if i == 0 else "the race"
        print(f"| {name} | {rs[0]['robots']} | {rs[0]['last'] + 1} | {med('fps'):.0f} | "
              f"{med('forward'):.2f} | {med('jump'):.2f} | {med('heap') / 1048576:.1f} |")


main()
