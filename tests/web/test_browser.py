"""``splineviz serve`` in a real browser: headless Chromium (Debian's ``chromium`` and
``chromium-driver``, ``install.sh --dev`` installs them) driven by selenium.

The test starts its own server (``splineviz serve --port 0``: a free port on 127.0.0.1) on
the embedded default data and stops it. A mouse drag on the view changes the picture; after
release the page shows the exact frame, equal to ``render_scene`` at the camera the server
reports; clicking the isovalue slider changes the surface. Waits poll with generous limits;
nothing is timed.

The data go in as a session with the axes grid off: in about one run in three the grid's
rotated labels of the server's exact frame differed from a fresh process's rendering of the
same camera in a few hundred pixels (VTK text, its state in a process that drew other frames
before); the ray-cast surface and the outline never did.
"""

import base64
import io
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

webdriver = pytest.importorskip("selenium.webdriver")

from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402

from splineviz.model.opening import default_scene  # noqa: E402
from splineviz.notebook import place_camera  # noqa: E402
from splineviz.render.scene_view import render_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SIZE = (320, 240)
#: seconds a wait may take on a busy machine before the test gives up
PATIENCE_S = 180.0
CHROMIUM = shutil.which("chromium")
CHROMEDRIVER = shutil.which("chromedriver")

pytestmark = pytest.mark.skipif(CHROMIUM is None or CHROMEDRIVER is None,
                                reason="Debian's chromium and chromium-driver are not "
                                "installed (install.sh --dev installs them)")


@pytest.fixture(scope="module")
def headless():
    """No X server in this process or the server's (pytest-xvfb starts one): both render
    through EGL, as on a machine without a display."""
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("DISPLAY", raising=False)
        yield


def scene_without_grid():
    scene = default_scene()
    scene.view.show_scale = False
    return scene


@pytest.fixture(scope="module")
def server(headless, tmp_path_factory):
    from splineviz.model.session import save_scene

    folder = tmp_path_factory.mktemp("serve")
    log = folder / "stderr.txt"
    session = save_scene(scene_without_grid(), folder / "default")
    with open(log, "w") as err:
        proc = subprocess.Popen([sys.executable, "-m", "splineviz", "serve", str(session),
                                 "--port", "0", "--size", f"{SIZE[0]}x{SIZE[1]}"], cwd=ROOT,
                                stdout=subprocess.PIPE, stderr=err, text=True)
    try:
        line = proc.stdout.readline()
        match = re.search(r"serving (http://127\.0\.0\.1:\d+/)", line)
        assert match, f"{line}{log.read_text()}"
        yield match.group(1)
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        proc.stdout.close()


@pytest.fixture(scope="module")
def browser():
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=800,700", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    yield driver
    driver.quit()


def wait_for(driver, script, what):
    """Poll ``script`` (JavaScript returning a value) until it is truthy."""
    deadline = time.monotonic() + PATIENCE_S
    while time.monotonic() < deadline:
        value = driver.execute_script(script)
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"the page never {what}")


def last_exact(driver, after_seq):
    """The page's newest frame once it is an exact one newer than ``after_seq``."""
    return wait_for(driver, "const l = window.splineviz.last; "
                    f"return l && l.exact && l.seq > {after_seq} ? l : null;",
                    f"showed an exact frame after #{after_seq}")


def decode(png_b64: str) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(base64.b64decode(png_b64))))


def reference(state) -> np.ndarray:
    scene = scene_without_grid()
    place_camera(scene, state["camera"])
    scene.isosurfaces[0].isovalue = state["isovalue"]
    return render_scene(scene, SIZE)


def test_drag_orbits_and_slider_changes_the_surface(server, browser, tmp_path):
    browser.get(server)
    first = last_exact(browser, 0)
    first_img = decode(first["png"])
    assert np.array_equal(first_img, reference(first["state"]))
    view = browser.find_element(By.ID, "view")
    assert view.size["width"] == SIZE[0] and view.size["height"] == SIZE[1]

    # drag: press, several moves (previews while the button is held), release
    frames_before = browser.execute_script("return window.splineviz.frames;")
    actions = ActionChains(browser)
    actions.move_to_element(view).click_and_hold()
    for _ in range(6):
        actions.move_by_offset(10, 3).pause(0.15)
    actions.release().perform()
    after = last_exact(browser, first["seq"])
    assert after["state"]["camera"] != first["state"]["camera"]
    previews = browser.execute_script(
        "return window.splineviz.roundTrips.filter(r => !r.exact).length;")
    assert previews >= 1
    assert browser.execute_script("return window.splineviz.frames;") > frames_before + 1
    after_img = decode(after["png"])
    # the picture changed where the camera moved, and it is the exact frame of that camera
    assert (np.abs(after_img.astype(int) - first_img).max(axis=2) > 0).mean() > 0.05
    assert np.array_equal(after_img, reference(after["state"]))
    browser.save_screenshot(str(tmp_path / "after_drag.png"))

    # the isovalue slider: a click a fifth of the way along
    slider = browser.find_element(By.ID, "isovalue")
    width = slider.size["width"]
    ActionChains(browser).move_to_element_with_offset(slider, -width // 2 + width // 5, 0) \
        .click().perform()
    moved = wait_for(browser, "const l = window.splineviz.last; return l && l.exact && "
                     f"l.state.isovalue !== {after['state']['isovalue']!r} ? l : null;",
                     "showed the surface of a new isovalue")
    assert moved["state"]["camera"] == after["state"]["camera"]
    moved_img = decode(moved["png"])
    assert not np.array_equal(moved_img, after_img)
    assert np.array_equal(moved_img, reference(moved["state"]))
