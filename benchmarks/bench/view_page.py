"""The view page of a large run in headless Chromium: its size, its first draw and a seek.

    decoy evaluate ../shared/data/esta_dust2_tside --no-combat --no-bomb --out RUN
    python benchmarks/bench/view_page.py RUN [--baseline-bytes N]

Prints the page's size (whole, per round, gzipped; with `--baseline-bytes`, the size of another
page of the same rounds, the ratio per round), the time from navigation until the page's
script has drawn its first round (`domContentLoadedEventEnd`: the script runs before that
event, and draws synchronously), the same for a round opened by the URL's fragment, and the
time of a seek and draw (the slider moved to a random time of a random round, timed inside
the page: median, 95th percentile and largest of `SEEKS`), with the machine. Measured, never
asserted: timings on these shared machines vary. It drives Chromium through tests/browser.py.
"""

from __future__ import annotations

import argparse
import gzip
import json
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

from browser import Browser, find_chromium  # noqa: E402

from decoy_cli.bench.machine import machine_line  # noqa: E402

SEEKS = 400
LOADS = 3

SEEK_SCRIPT = """
(() => {
  const slider = document.getElementById('time'), select = document.getElementById('round-select');
  const rounds = select.options.length, times = [];
  let seed = 7;
  const random = () => { seed = (seed * 16807) % 2147483647; return seed / 2147483647; };
  for (let k = 0; k < SEEKS; k++) {
    if (k % 50 === 0) {
      select.value = String(Math.floor(random() * rounds));
      select.dispatchEvent(new Event('change'));
    }
    const lo = Number(slider.min), hi = Number(slider.max);
    const start = performance.now();
    slider.value = String(lo + random() * (hi - lo));
    slider.dispatchEvent(new Event('input'));
    times.push(performance.now() - start);
  }
  return times;
})()
"""


def first_draw_ms(browser: Browser, url: str) -> float:
    browser.call("Page.navigate", {"url": "about:blank"}, session=True)
    browser.call("Page.navigate", {"url": url}, session=True)
    browser.wait_for("document.body && document.body.dataset.ready === '1'", timeout_s=60)
    browser.wait_for("performance.getEntriesByType('navigation')[0].domContentLoadedEventEnd > 0")
    return float(
        browser.evaluate("performance.getEntriesByType('navigation')[0].domContentLoadedEventEnd")
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("run", type=Path, help="an evaluate run's folder (its view.html)")
    parser.add_argument("--baseline-bytes", type=int, help="another page's size, same rounds")
    args = parser.parse_args()
    page = args.run / "view.html"
    html = page.read_bytes()
    found = html.split(b'id="data">', 1)[1].split(b"</script>", 1)[0]
    rounds = len(json.loads(found)["rounds"])
    zipped = len(gzip.compress(html, 6))
    print(machine_line())
    print(f"page: {page} ({rounds} rounds)")
    print(
        f"size: {len(html) / 1e6:.2f} MB, {len(html) / rounds / 1e3:.1f} kB a round, "
        f"{zipped / 1e6:.2f} MB gzipped"
    )
    if args.baseline_bytes:
        print(
            f"baseline: {args.baseline_bytes / 1e6:.2f} MB, "
            f"{args.baseline_bytes / rounds / 1e3:.1f} kB a round; "
            f"ratio {len(html) / args.baseline_bytes:.2f}"
        )
    executable = find_chromium()
    if executable is None:
        raise SystemExit("no Chromium to drive (DECOY_CHROMIUM names one)")
    with Browser(executable) as browser:
        browser.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1600, "height": 1000, "deviceScaleFactor": 1, "mobile": False},
            session=True,
        )
        url = page.resolve().as_uri()
        loads = [first_draw_ms(browser, url) for _ in range(LOADS)]
        print(
            f"first draw: median {statistics.median(loads):.0f} ms of {LOADS} loads "
            f"({min(loads):.0f}-{max(loads):.0f})"
        )
        label = browser.evaluate(
            f"document.getElementById('round-select').options[{rounds - 1}].text"
        )
        fragment = first_draw_ms(browser, f"{url}#round={label}&t=30")
        print(f"first draw of the last round by the URL's fragment: {fragment:.0f} ms")
        times = sorted(browser.evaluate(SEEK_SCRIPT.replace("SEEKS", str(SEEKS))))
        p95 = times[int(0.95 * (len(times) - 1))]
        print(
            f"seek and draw: median {statistics.median(times):.2f} ms, 95th percentile "
            f"{p95:.2f} ms, largest {times[-1]:.2f} ms ({SEEKS} seeks over random rounds)"
        )
        errors = browser.console_errors()
        if errors:
            print(f"console errors: {errors}")


if __name__ == "__main__":
    main()
