"""The real-browser test of `ibeam serve`: headless Chromium loads the
page, sees the render, drags and sees the view turn, saves an edit and
sees it, saves a broken edit and sees the located error with the last
good image kept, then fixes it. Run by .ci/browser-test."""

import base64
import os
import shutil
import subprocess
import sys
import tempfile
import time

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

SCENE = """object ball = sphere(0.8) { color = (0.8, 0.3, 0.2); }
object block = translate(box(0.4, 0.4, 0.4), 1.1, 0, 0) { color = (0.2, 0.5, 0.8); }
camera { eye = (0, 1, 5); target = (0, 0, 0); up = (0, 1, 0); fov = 40; }
light { direction = (-0.5, -1, -0.7); shadows = true; }
bounds = (-2, -2, -2) .. (2, 2, 2);
"""
PATIENCE = 60


def main(ibeam):
    start = time.monotonic()
    work = tempfile.mkdtemp(prefix="ibeam-browser-")
    scene = os.path.join(work, "scene.ib")
    with open(scene, "w") as f:
        f.write(SCENE)
    server = subprocess.Popen(
        [ibeam, "serve", scene, "--port", "0", "--size", "160x120"],
        stdout=subprocess.PIPE, text=True)
    driver = None
    try:
        line = server.stdout.readline()
        url = next(w for w in line.split() if w.startswith("http://"))
        driver = chromium(work)
        run(driver, url, scene)
    finally:
        if driver is not None:
            driver.quit()
        server.kill()
        server.wait()
        shutil.rmtree(work, ignore_errors=True)
    print(f"browser-test: passed in {time.monotonic() - start:.1f} s")


def chromium(work):
    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for a in ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
              "--no-first-run", "--disable-background-networking",
              "--disable-component-update", "--disable-sync",
              "--disable-dev-shm-usage", "--window-size=1200,800",
              "--user-data-dir=" + os.path.join(work, "profile")]:
        opts.add_argument(a)
    return webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)


def wait(driver, what, ok):
    try:
        return WebDriverWait(driver, PATIENCE, poll_frequency=0.05).until(lambda d: ok())
    except Exception as e:
        sys.exit(f"browser-test: FAILED waiting for {what}: {e!r}\n"
                 f"error box: {driver.find_element(By.ID, 'error').text!r}")


def shown(driver):
    """The full image on the page (not a preview): its camera and pixels."""
    img = driver.find_element(By.ID, "view")
    ready = driver.execute_script(
        "const i = arguments[0]; return i.complete && i.naturalWidth === 160"
        " && i.dataset.preview === '0';", img)
    if not ready:
        return None
    return img.get_attribute("data-camera"), img.get_attribute("data-generation"), pixels(driver)


def pixels(driver):
    # The image's own pixels, read back through a canvas.
    url = driver.execute_script(
        "const i = document.getElementById('view'); const c = document.createElement('canvas');"
        " c.width = i.naturalWidth; c.height = i.naturalHeight;"
        " c.getContext('2d').drawImage(i, 0, 0); return c.toDataURL('image/png');")
    return base64.b64decode(url.split(",", 1)[1])


def run(driver, url, scene):
    driver.get(url)
    first = wait(driver, "the first render", lambda: shown(driver))
    assert first[0].startswith("--eye 0,1,5 "), first[0]
    assert "evaluations" in driver.find_element(By.ID, "stats").text
    assert "object ball" in driver.find_element(By.ID, "ir").get_attribute("textContent")

    img = driver.find_element(By.ID, "view")
    chain = ActionChains(driver).move_to_element(img).click_and_hold()
    for _ in range(6):
        chain = chain.move_by_offset(15, 4).pause(0.05)
    chain.release().perform()
    turned = wait(driver, "the turned view",
                  lambda: (s := shown(driver)) and s[0] != first[0] and s)
    assert turned[2] != first[2], "the image did not change after the drag"
    flags = driver.find_element(By.ID, "flags").text
    assert flags == turned[0] and "--eye" in flags and "--fov 40" in flags, flags

    with open(scene, "w") as f:
        f.write(SCENE.replace("sphere(0.8)", "sphere(0.4)"))
    edited = wait(driver, "the edit",
                  lambda: (s := shown(driver)) and s[1] != turned[1] and s)
    assert edited[2] != turned[2], "the image did not change after the edit"
    assert edited[0] == turned[0], "the edit moved the camera"

    with open(scene, "w") as f:
        f.write(SCENE.replace("sphere(0.8)", "sphere(0.4 +)"))
    box = driver.find_element(By.ID, "error")
    wait(driver, "the error", lambda: box.is_displayed() and "error:" in box.text)
    assert "scene.ib:1:" in box.text, box.text
    time.sleep(0.5)
    kept = shown(driver)
    assert kept is not None and kept[2] == edited[2], "the last good image was not kept"

    with open(scene, "w") as f:
        f.write(SCENE)
    wait(driver, "the error to clear", lambda: not box.is_displayed())


if __name__ == "__main__":
    main(sys.argv[1])
