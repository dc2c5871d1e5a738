"""Round trip of an interaction in headless Chromium: mouse event to new frame in the page.

``splineviz serve`` (previews while the button is held, the exact frame after release) against
pyvista's trame backend showing VTK's flying-edges mesh of the same data (server-side
rendering, images streamed), in the same browser at the same view size. A script injected
before each page loads timestamps the pointer events (capture phase) and every websocket
message of a picture's size; a drag of 10 steps 0.4 s apart gives one round trip per step
(the first picture after it) and the release one (splineviz: its exact frame; trame: the
last picture within 3 s of the release); a continuous drag (40 steps 50 ms apart) gives the
pictures per second while dragging. Prints the medians; the screenshots go to
``$SPLINEVIZ_BENCH_OUT`` (default: the test's temporary folder).
"""

import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

webdriver = pytest.importorskip("selenium.webdriver")

pytestmark = [pytest.mark.bench,
              pytest.mark.skipif(shutil.which("chromium") is None
                                 or shutil.which("chromedriver") is None,
                                 reason="chromium and chromium-driver are not installed")]

ROOT = Path(__file__).resolve().parents[2]
SIZE = (640, 480)
#: a websocket message at least this large carries a picture
PICTURE_BYTES = 2_000

HOOK = """
window.__rt = {events: [], msgs: []};
for (const type of ["pointerdown", "pointermove", "pointerup"]) {
  document.addEventListener(type, (e) => window.__rt.events.push([type, performance.now()]),
                            true);
}
const Native = window.WebSocket;
window.WebSocket = function (...args) {
  const ws = new Native(...args);
  ws.addEventListener("message", (ev) => {
    const d = ev.data;
    const n = typeof d === "string" ? d.length : (d.size || d.byteLength || 0);
    window.__rt.msgs.push([performance.now(), n]);
  });
  return ws;
};
window.WebSocket.prototype = Native.prototype;
for (const k of ["CONNECTING", "OPEN", "CLOSING", "CLOSED"]) window.WebSocket[k] = Native[k];
"""


def _start(cmd, log):
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=log, text=True)
    line = proc.stdout.readline()
    match = re.search(r"serving (http://127\.0\.0\.1:\d+/)", line)
    if not match:
        proc.kill()
        proc.wait()
        proc.stdout.close()
        raise AssertionError(f"server did not start: {line}")
    return proc, match.group(1)


def _stop(proc):
    proc.terminate()
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    proc.stdout.close()


def _browser():
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=900,800", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)
    driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": HOOK})
    return driver


def _drag(driver, element, steps=10, step_px=8, pause_s=0.4):
    from selenium.webdriver.common.action_chains import ActionChains

    driver.execute_script("window.__rt.events = []; window.__rt.msgs = [];")
    actions = ActionChains(driver).move_to_element(element).click_and_hold()
    for _ in range(steps):
        actions.move_by_offset(step_px, step_px // 3).pause(pause_s)
    actions.release().perform()
    time.sleep(3.0)
    return driver.execute_script("return window.__rt;")


def _round_trips(rt):
    """Per move: ms to the first picture after it (before the next event); the release: ms
    to the last picture within 3 s of it."""
    pictures = [t for t, n in rt["msgs"] if n >= PICTURE_BYTES]
    events = [(kind, t) for kind, t in rt["events"] if kind in ("pointermove", "pointerup")]
    moves = []
    for i, (kind, t) in enumerate(events):
        if kind != "pointermove":
            continue
        following = events[i + 1][1] if i + 1 < len(events) else float("inf")
        after = [p for p in pictures if t < p < following]
        if after:
            moves.append(after[0] - t)
    ups = [t for kind, t in events if kind == "pointerup"]
    release = None
    if ups:
        late = [p for p in pictures if ups[-1] < p < ups[-1] + 3000.0]
        release = late[-1] - ups[-1] if late else None
    return moves, release


def _drag_rate(driver, element):
    """(pictures, mouse moves) per second during a continuous drag (40 steps 50 ms apart)."""
    rt = _drag(driver, element, steps=40, step_px=4, pause_s=0.05)
    moves = [t for kind, t in rt["events"] if kind == "pointermove"]
    ups = [t for kind, t in rt["events"] if kind == "pointerup"]
    if not moves or not ups:
        return None
    start, end = moves[0], ups[-1]
    pictures = [t for t, n in rt["msgs"] if n >= PICTURE_BYTES and start < t <= end]
    seconds = (end - start) / 1000.0
    return len(pictures) / seconds, len(moves) / seconds


def _largest_view(driver):
    from selenium.webdriver.common.by import By

    candidates = driver.find_elements(By.CSS_SELECTOR, "img, canvas, .vtk-container, div")
    sized = [(e.size["width"] * e.size["height"], e) for e in candidates
             if e.is_displayed() and e.size["width"] <= SIZE[0] + 10
             and e.size["height"] <= SIZE[1] + 10]
    return max(sized, key=lambda s: s[0])[1]


def test_round_trip_splineviz_vs_pyvista_trame(tmp_path):
    from selenium.webdriver.common.by import By

    out = Path(os.environ.get("SPLINEVIZ_BENCH_OUT") or tmp_path)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with open(tmp_path / "servers.log", "w") as log:
        driver = _browser()
        try:
            proc, url = _start([sys.executable, "-m", "splineviz", "serve", "--port", "0",
                                "--size", f"{SIZE[0]}x{SIZE[1]}"], log)
            try:
                driver.get(url)
                deadline = time.monotonic() + 180
                while not driver.execute_script(
                        "return window.splineviz && window.splineviz.exactFrames > 0"):
                    assert time.monotonic() < deadline
                    time.sleep(0.2)
                driver.save_screenshot(str(out / "splineviz_first.png"))
                driver.execute_script("window.splineviz.roundTrips = [];")
                view = driver.find_element(By.ID, "view")
                rt = _drag(driver, view)
                driver.save_screenshot(str(out / "splineviz_after_drag.png"))
                moves, release = _round_trips(rt)
                page = driver.execute_script("return window.splineviz.roundTrips;")
                exact = [r["ms"] for r in page if r["exact"]]
                previews = [r["ms"] for r in page if not r["exact"]]
                rows.append(("splineviz serve: preview (move -> picture message)", moves))
                rows.append(("splineviz serve: preview (event -> frame on screen, page)",
                             previews))
                rows.append(("splineviz serve: exact after release (page)", exact))
                rate = _drag_rate(driver, view)
                rows.append(("splineviz serve: pictures/s (mouse moves/s) in a continuous drag",
                             [] if rate is None else list(rate)))
            finally:
                _stop(proc)
            peer = Path(__file__).with_name("pyvista_trame_peer.py")
            proc, url = _start([sys.executable, str(peer), "0", str(SIZE[0]), str(SIZE[1])],
                               log)
            try:
                driver.get(url)
                time.sleep(8.0)  # the page builds its view and asks for the first picture
                driver.save_screenshot(str(out / "trame_first.png"))
                rt = _drag(driver, _largest_view(driver))
                driver.save_screenshot(str(out / "trame_after_drag.png"))
                moves, release = _round_trips(rt)
                rows.append(("pyvista trame (flying edges): move -> picture", moves))
                rows.append(("pyvista trame (flying edges): release -> last picture",
                             [] if release is None else [release]))
                rate = _drag_rate(driver, _largest_view(driver))
                rows.append(("pyvista trame (flying edges): pictures/s (mouse moves/s) in a "
                             "continuous drag", [] if rate is None else list(rate)))
            finally:
                _stop(proc)
        finally:
            driver.quit()
    print(f"\nround trips in headless Chromium, {SIZE[0]}x{SIZE[1]} view (ms; rates in 1/s):")
    for name, values in rows:
        if "continuous" in name and values:
            print(f"  {name}: {values[0]:.1f} ({values[1]:.1f})")
        elif values:
            print(f"  {name}: median {np.median(values):.0f}, min {np.min(values):.0f}, "
                  f"max {np.max(values):.0f} (n={len(values)})")
        else:
            print(f"  {name}: no picture")
    print(f"  screenshots in {out}")
    assert rows[0][1] and rows[2][1]
