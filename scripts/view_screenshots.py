"""The README's screenshots of the view page, at three window sizes, from the shipped sample:

    python scripts/view_screenshots.py [RUN]

evaluates examples/sample into a temporary folder (or takes the `decoy evaluate` run RUN),
opens its view.html in headless Chromium (tests/browser.py) at a phone's, a small laptop's and
a desktop's window, on round 1 at 40 s, and writes docs/images/view-WIDTH.png, each scaled
down so the files stay small.
"""

from __future__ import annotations

import base64
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from browser import Browser, find_chromium  # noqa: E402

SIZES = ((390, 844, 0.6), (1024, 768, 0.6), (1920, 1080, 0.45))
"""Window width and height (CSS pixels) and the scale of the image taken."""
OUT = ROOT / "docs" / "images"


def shoot(page: Path) -> list[Path]:
    executable = find_chromium()
    if executable is None:
        raise SystemExit("no Chromium to drive (DECOY_CHROMIUM names one)")
    written = []
    with Browser(executable) as browser:
        for width, height, scale in SIZES:
            browser.call(
                "Emulation.setDeviceMetricsOverride",
                {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": width < 600},
                session=True,
            )
            browser.open(page)
            browser.evaluate(
                "(() => { const s = document.getElementById('time'); s.value = '40'; "
                "s.dispatchEvent(new Event('input')); "
                "document.getElementById('round').scrollIntoView(); })()"
            )
            top = browser.evaluate("scrollY")
            clip = {"x": 0, "y": top, "width": width, "height": height, "scale": scale}
            data = browser.call(
                "Page.captureScreenshot", {"format": "png", "clip": clip}, session=True
            )["data"]
            path = OUT / f"view-{width}.png"
            path.write_bytes(base64.b64decode(data))
            written.append(path)
    return written


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        if len(sys.argv) > 1:
            run = Path(sys.argv[1])
        else:
            run = Path(folder) / "evaluate"
            command = ["decoy", "evaluate", str(ROOT / "examples" / "sample"), "--out", str(run)]
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        for path in shoot(run / "view.html"):
            print(f"{path.relative_to(ROOT)}: {path.stat().st_size / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
