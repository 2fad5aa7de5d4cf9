#!/usr/bin/env python3
"""`fspec view` in a real browser, and its timing.

    tools/view_browser.py test FSPEC [OUT_DIR]
        Headless Chromium (Debian's chromium + chromium-driver, Selenium
        from pip) against `fspec view cornell`: waits for the passes, takes
        element screenshots of the image, switches the transport to sampled,
        orbits the camera, and checks each screenshot: not black, different
        from the one before, and (while the page's settings have a
        `fspec render` equivalent) equal to a file render of the same
        settings within the noise of that render; toggles the split view
        (Fourier | sampled at equal time): not black, each half's passes
        shown, and the halves' noise in another proportion than in a
        one-transport image (below). Prints SKIP and exits 0 where no
        browser or Selenium exists.

    tools/view_browser.py measure FSPEC [--side 512] [--scene cornell]
        Plain HTTP, no browser: time (wall and CPU of the server process)
        from opening the page's event stream to the first full frame, time
        from a camera change to the new generation's first frame, passes
        per second, the time of a click's spectrum, and each half's passes
        and seconds after SPLIT_MEASURE_S of the split view.

    tools/view_browser.py screenshot FSPEC PNG
        A small screenshot of the page on the lamps scene in split view
        with a pixel's spectrum (for the README).

Why Python: Selenium's Python binding is the reference one, Debian ships
the driver, and the test needs nothing compiled; the PNG decoding below is
the standard library's zlib (no imaging package).

The noise tolerance: two file renders with seeds 0 and 1 differ by the
render's noise, `d_noise` (mean absolute difference of the 8-bit values);
the screenshot must be within `d_noise / 2` of the seed-0 render, the same
settings bit for bit. The negative control checks that the seed-1 render,
as different as noise makes it, fails that tolerance.

The split view's noise: the chroma roughness of a half (mean absolute
difference of R−G and B−G between horizontal neighbours) measures its
colour noise plus its content's edges. In a one-transport image the right
half's roughness over the left's is fixed by the content and that
transport's noise; the split image's ratio, Fourier left and sampled
right, must exceed the Fourier image's by SPLIT_NOISE_RATIO: the sampled
half carries the wavelength sampling's colour noise. The negative control:
the one-transport sampled image must not pass that test.
"""

import http.client
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import time
import zlib

# How long any wait may last, seconds (a debug build on a loaded machine).
DEADLINE_S = 180
# The test's image: small, so that a debug build renders it in seconds.
TEST_SIDE = 96
TEST_PASSES = 8
# How long `measure` lets the split view run, seconds.
SPLIT_MEASURE_S = 10
# Mean 8-bit value below which a screenshot counts as black.
BLACK_MEAN = 2.0
# How much more the split view's right/left chroma roughness must be than a
# one-transport image's (module docs). Measured with the default Sobol
# sampler at TEST_SIDE and TEST_PASSES: the split image 2.48x the Fourier
# image's ratio, the sampled image alone 1.32x (Sobol lowers the sampled
# half's noise; with independent numbers they were 5.2x and 1.2x). The
# bound is their geometric mean, so each side is 1.37x away from it.
SPLIT_NOISE_RATIO = 1.8


def decode_png(data):
    """(width, height, channels, bytes) of an 8-bit non-interlaced PNG."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    if depth != 8 or interlace != 0:
        raise ValueError("only 8-bit non-interlaced PNGs")
    raw = zlib.decompress(idat)
    stride = width * channels
    out = bytearray(height * stride)
    prev = bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        out[y * stride : (y + 1) * stride] = line
        prev = line
    return width, height, channels, bytes(out)


def rgb(png):
    """(width, height, RGB bytes) of a PNG."""
    width, height, channels, data = decode_png(png)
    if channels == 3:
        return width, height, data
    rgb_bytes = bytearray()
    for i in range(0, len(data), channels):
        rgb_bytes += data[i : i + 3]
    return width, height, bytes(rgb_bytes)


def mean_abs_difference(a, b):
    if len(a) != len(b):
        raise ValueError(f"sizes differ: {len(a)} and {len(b)} values")
    return sum(abs(x - y) for x, y in zip(a, b)) / len(a)


def start_view(fspec, *args):
    """`fspec view …` and the address it prints."""
    process = subprocess.Popen(
        [fspec, "view", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    line = process.stdout.readline()
    if "http://" not in line:
        process.kill()
        raise RuntimeError(f"fspec view printed {line!r}: {process.stderr.read()}")
    url = line.split("open ")[1].split()[0]
    return process, url


def stop_view(process):
    process.send_signal(signal.SIGINT)  # as Ctrl-C: a graceful stop
    try:
        process.wait(timeout=30)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def file_render(fspec, command, out, *extra):
    """Runs the page's `fspec render …` line (plus `extra`) into `out`."""
    words = command.split()[2:]  # drop "fspec render"
    subprocess.run(
        [fspec, "render", *words, *extra, "--quiet", "--out", out],
        check=True,
        capture_output=True,
    )
    with open(out, "rb") as f:
        return rgb(f.read())[2]


def browser_or_skip():
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        print("SKIP: the browser test needs Selenium (pip install selenium)")
        sys.exit(0)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver_path = shutil.which("chromedriver")
    if not chromium or not driver_path:
        print("SKIP: the browser test needs chromium and chromedriver (apt-get install chromium chromium-driver)")
        sys.exit(0)
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1000,700",
                 "--force-device-scale-factor=1", "--force-color-profile=srgb"):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(driver_path), options=options)


def wait_for(driver, generation, passes):
    """Waits until the image shows `passes` passes of `generation`."""
    start = time.time()
    while time.time() - start < DEADLINE_S:
        shown = driver.execute_script(
            "const v = document.getElementById('view');"
            "return [Number(v.dataset.generation), Number(v.dataset.passes), v.complete];"
        )
        if shown[0] == generation and shown[1] == passes and shown[2]:
            # The data URL is decoded before `complete`; one frame more to paint.
            time.sleep(0.3)
            return
        time.sleep(0.1)
    raise TimeoutError(f"no frame of generation {generation} with {passes} passes")


def screenshot(driver, out_dir, name):
    from selenium.webdriver.common.by import By

    png = driver.find_element(By.ID, "view").screenshot_as_png
    with open(os.path.join(out_dir, name), "wb") as f:
        f.write(png)
    return rgb(png)


def chroma_roughness(width, height, data, columns):
    """Mean |Δ(R−G)| + |Δ(B−G)| between horizontal neighbours in `columns`."""
    total, count = 0, 0
    for y in range(height):
        row = y * width * 3
        for x in columns[:-1]:
            a, b = row + 3 * x, row + 3 * (x + 1)
            total += abs((data[a] - data[a + 1]) - (data[b] - data[b + 1]))
            total += abs((data[a + 2] - data[a + 1]) - (data[b + 2] - data[b + 1]))
            count += 1
    return total / max(count, 1)


def halves_ratio(width, height, data):
    """Right half's chroma roughness over the left half's."""
    half = width // 2
    left = chroma_roughness(width, height, data, list(range(0, half)))
    right = chroma_roughness(width, height, data, list(range(half, width)))
    return right / max(left, 1e-9)


def wait_for_complete(driver, generation):
    """Waits until the image shows the last frame of `generation`."""
    start = time.time()
    while time.time() - start < DEADLINE_S:
        shown = driver.execute_script(
            "const v = document.getElementById('view');"
            "return [Number(v.dataset.generation), v.dataset.complete, v.complete];"
        )
        if shown[0] == generation and shown[1] == "true" and shown[2]:
            time.sleep(0.3)
            return
        time.sleep(0.1)
    raise TimeoutError(f"generation {generation} never completed")


def check(condition, message):
    if not condition:
        raise AssertionError(message)
    print(f"ok: {message}")


def test(fspec, out_dir):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    os.makedirs(out_dir, exist_ok=True)
    driver = browser_or_skip()
    process = None
    try:
        process, url = start_view(
            fspec, "cornell", "--width", str(TEST_SIDE), "--height", str(TEST_SIDE),
            "--max-passes", str(TEST_PASSES),
        )
        driver.get(url)
        wait_for(driver, 0, TEST_PASSES)
        width, height, fourier = screenshot(driver, out_dir, "fourier.png")
        check((width, height) == (TEST_SIDE, TEST_SIDE), f"screenshot is {width}×{height}")
        check(sum(fourier) / len(fourier) > BLACK_MEAN, "the Fourier image is not black")
        compare_with_file(fspec, driver, fourier, out_dir, "fourier")

        Select(driver.find_element(By.ID, "transport")).select_by_value("sampled")
        wait_for(driver, 1, TEST_PASSES)
        _, _, sampled = screenshot(driver, out_dir, "sampled.png")
        check(sum(sampled) / len(sampled) > BLACK_MEAN, "the sampled image is not black")
        check(mean_abs_difference(sampled, fourier) > 0, "the transport change changed the image")
        compare_with_file(fspec, driver, sampled, out_dir, "sampled")

        # Split view, at the same camera and passes limit.
        driver.find_element(By.ID, "split").click()
        wait_for_complete(driver, 2)
        _, _, split = screenshot(driver, out_dir, "split.png")
        check(sum(split) / len(split) > BLACK_MEAN, "the split image is not black")
        labels = [driver.find_element(By.ID, i).text for i in ("split-left", "split-right")]
        check("Fourier" in labels[0] and "spp" in labels[0] and "sampled" in labels[1]
              and "spp" in labels[1], f"each half's passes are shown: {labels}")
        split_ratio = halves_ratio(TEST_SIDE, TEST_SIDE, split)
        fourier_ratio = halves_ratio(TEST_SIDE, TEST_SIDE, fourier)
        sampled_ratio = halves_ratio(TEST_SIDE, TEST_SIDE, sampled)
        check(split_ratio > SPLIT_NOISE_RATIO * fourier_ratio,
              f"the halves differ in noise: right/left roughness {split_ratio:.2f} split, "
              f"{fourier_ratio:.2f} Fourier alone")
        check(sampled_ratio <= SPLIT_NOISE_RATIO * fourier_ratio,
              f"negative control: sampled alone ({sampled_ratio:.2f}) does not pass")
        driver.find_element(By.ID, "split").click()
        wait_for(driver, 3, TEST_PASSES)
        _, _, unsplit = screenshot(driver, out_dir, "unsplit.png")

        view = driver.find_element(By.ID, "view")
        ActionChains(driver).move_to_element(view).click_and_hold().move_by_offset(30, 10) \
            .pause(0.2).move_by_offset(30, 10).release().perform()
        # Each camera message restarts the render: wait for the last one.
        start = time.time()
        while time.time() - start < DEADLINE_S:
            state = json.loads(driver.execute_script(
                "return fetch('/api/state').then(r => r.text())"))
            if state["settings"]["camera"] is not None:
                break
            time.sleep(0.1)
        generation = state["generation"]
        wait_for(driver, generation, TEST_PASSES)
        _, _, orbited = screenshot(driver, out_dir, "orbited.png")
        check(sum(orbited) / len(orbited) > BLACK_MEAN, "the orbited image is not black")
        moved = mean_abs_difference(orbited, unsplit)
        check(moved > 1.0, f"orbiting changed the image (mean difference {moved:.2f})")
        command = driver.find_element(By.ID, "command").text
        check(command == "", "a moved camera has no fspec render equivalent")
    finally:
        driver.quit()
        if process:
            stop_view(process)
    print("browser test passed")


def compare_with_file(fspec, driver, shown, out_dir, name):
    from selenium.webdriver.common.by import By

    command = driver.find_element(By.ID, "command").text.removeprefix("same image: ")
    check(command.startswith("fspec render"), f"the page names its render: {command}")
    same = file_render(fspec, command, os.path.join(out_dir, f"{name}-file.png"))
    other_seed = file_render(fspec, command, os.path.join(out_dir, f"{name}-seed1.png"), "--seed", "1")
    noise = mean_abs_difference(same, other_seed)
    tolerance = noise / 2
    difference = mean_abs_difference(shown, same)
    check(noise > 0, f"{name}: seeds 0 and 1 differ by noise {noise:.3f}")
    check(difference <= tolerance,
          f"{name}: screenshot within {tolerance:.3f} of the file render (difference {difference:.3f})")
    control = mean_abs_difference(shown, other_seed)
    check(control > tolerance, f"{name}: negative control, the seed-1 render is {control:.3f} away")


class Events:
    """The page's event stream read with http.client (no browser)."""

    def __init__(self, host, port):
        self.connection = http.client.HTTPConnection(host, port, timeout=DEADLINE_S)
        self.connection.request("GET", "/api/events")
        self.response = self.connection.getresponse()

    def frame(self):
        kind = None
        while True:
            line = self.response.fp.readline().decode().strip()
            if line.startswith("event:"):
                kind = line[6:].strip()
            elif line.startswith("data:") and kind in ("frame", "error"):
                data = json.loads(line[5:])
                if kind == "error":
                    raise RuntimeError(data["error"])
                return data


def post(host, port, body):
    connection = http.client.HTTPConnection(host, port, timeout=DEADLINE_S)
    connection.request("POST", "/api/settings", json.dumps(body), {"Content-Type": "application/json"})
    reply = json.loads(connection.getresponse().read())
    connection.close()
    return reply


def cpu_seconds(pid):
    """User + system CPU seconds of a process so far (/proc/PID/stat)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(fspec, side, scene, passes):
    process, url = start_view(fspec, scene, "--width", str(side), "--height", str(side),
                              "--max-passes", str(passes))
    try:
        host, port = url.split("//")[1].strip("/").split(":")
        cpu_before = cpu_seconds(process.pid)
        opened = time.perf_counter()
        events = Events(host, int(port))
        first = events.frame()
        first_s = time.perf_counter() - opened
        first_cpu = cpu_seconds(process.pid) - cpu_before
        frame = first
        while frame["passes"] < passes:
            frame = events.frame()
        rate = frame["passes"] / (frame["elapsed_ms"] / 1e3)
        camera = frame["camera"]
        moved = dict(position=[p + 0.05 for p in camera["position"]],
                     target=[p + d * camera["pivot_distance"] for p, d in zip(camera["position"], camera["forward"])],
                     up=camera["world_up"], fov_deg=camera["fov_deg"])
        sent = time.perf_counter()
        generation = post(host, int(port), {"camera": moved})["generation"]
        while frame["generation"] != generation:
            frame = events.frame()
        restart_s = time.perf_counter() - sent
        # A click: the pixel at the centre traced both ways.
        clicked = time.perf_counter()
        cpu_clicked = cpu_seconds(process.pid)
        connection = http.client.HTTPConnection(host, int(port), timeout=DEADLINE_S)
        connection.request("GET", f"/api/spectrum?x={side // 2}&y={side // 2}")
        spectrum = json.loads(connection.getresponse().read())
        connection.close()
        probe_s = time.perf_counter() - clicked
        probe_cpu = cpu_seconds(process.pid) - cpu_clicked
        # The split view: each half's passes and time after a while.
        generation = post(host, int(port), {
            "split": {"kind": "sampled", "wavelengths": 4, "sampling": "hero"},
            "max_passes": 1 << 20})["generation"]
        started = time.perf_counter()
        while frame["generation"] != generation or time.perf_counter() - started < SPLIT_MEASURE_S:
            frame = events.frame()
        left, right = frame["split"]["left"], frame["split"]["right"]
        print(f"{scene} {side}×{side}: first full frame {first_s * 1e3:.0f} ms, {first_cpu:.2f} CPU-s "
              f"after opening the page ({first['passes']} pass, scene built on open); "
              f"{rate:.2f} passes/s over {passes} passes; "
              f"camera change to the new first frame {restart_s * 1e3:.0f} ms; "
              f"spectrum of the centre pixel {probe_s * 1e3:.0f} ms, {probe_cpu:.2f} CPU-s "
              f"({spectrum.get('fourier_paths')} + {spectrum.get('sampled', {}).get('paths')} paths); "
              f"split view after {SPLIT_MEASURE_S} s: Fourier {left['passes']} passes in "
              f"{left['seconds']:.2f} s, sampled {right['passes']} passes in {right['seconds']:.2f} s; "
              f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    finally:
        stop_view(process)


def docs_screenshot(fspec, out):
    driver = browser_or_skip()
    process = None
    try:
        process, url = start_view(fspec, "lamps", "--width", "256", "--height", "256",
                                  "--max-passes", "64")
        driver.set_window_size(760, 900)
        driver.get(url)
        wait_for(driver, 0, 64)
        from selenium.webdriver.common.action_chains import ActionChains
        from selenium.webdriver.common.by import By

        # The split view, Fourier | sampled at equal time, to its end.
        driver.find_element(By.ID, "split").click()
        wait_for_complete(driver, 1)
        # A click on the image plots that pixel's spectrum both ways.
        view = driver.find_element(By.ID, "view")
        ActionChains(driver).move_to_element_with_offset(view, -40, 60).click().perform()
        start = time.time()
        while "paths" not in driver.find_element(By.ID, "spectrum-caption").text:
            if time.time() - start > DEADLINE_S:
                raise TimeoutError("no spectrum")
            time.sleep(0.2)
        driver.save_screenshot(out)
    finally:
        driver.quit()
        if process:
            stop_view(process)


def main(argv):
    if len(argv) < 3 or argv[1] not in ("test", "measure", "screenshot"):
        print(__doc__)
        return 2
    fspec = argv[2]
    if argv[1] == "test":
        test(fspec, argv[3] if len(argv) > 3 else "target/view-browser")
    elif argv[1] == "measure":
        side = int(argv[argv.index("--side") + 1]) if "--side" in argv else 512
        scene = argv[argv.index("--scene") + 1] if "--scene" in argv else "cornell"
        passes = int(argv[argv.index("--passes") + 1]) if "--passes" in argv else 32
        measure(fspec, side, scene, passes)
    else:
        docs_screenshot(fspec, argv[3])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
