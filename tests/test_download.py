"""`decoy download` against a local HTTP server on 127.0.0.1 serving generated ESTA matches.

The server maps URL paths to behaviours: a fixture match (tests/esta_fixtures.py) under
`lan/` or `online/`, a match of another map, HTML instead of xz, a Git LFS pointer, corrupt
xz, a body cut short of its Content-Length, a server error, and an answer that comes too late.
Every other path is a 404. It counts the requests, so a skipped download can be checked.
"""

from __future__ import annotations

import hashlib
import http.server
import lzma
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.errors import DownloadError
from decoy_cli.esta.download import (
    ESTA_BASE_URL,
    download_match,
    match_urls,
    parse_match_id,
    verify_file,
)

runner = CliRunner()
WIDE = {"COLUMNS": "250"}

LAN_ID = "0013db25-4444-452b-980b-7702dc6fb810"
ONLINE_ID = "1f402c8a-95c3-4864-8530-e0b15eaf4b00"
SLOW_S = 1.5


@dataclass
class Site:
    """What the server answers, and what it was asked."""

    files: dict[str, bytes] = field(default_factory=dict)
    behaviours: dict[str, str] = field(default_factory=dict)
    requests: list[str] = field(default_factory=list)
    base_url: str = ""


def _handler(site: Site) -> type[http.server.BaseHTTPRequestHandler]:
    class Handler(http.server.BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: object) -> None:
            """Quiet: the tests read `site.requests` instead."""

        def do_GET(self) -> None:
            path = self.path.lstrip("/")
            site.requests.append(path)
            behaviour = site.behaviours.get(path)
            if behaviour == "error":
                self.send_error(503, "Service Unavailable")
                return
            if behaviour == "slow":
                time.sleep(SLOW_S)
            body = site.files.get(path)
            if body is None:
                self.send_error(404, "Not Found")
                return
            self.send_response(200)
            self.send_header("Content-Type", "application/octet-stream")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            if behaviour == "truncated":
                self.wfile.write(body[: len(body) // 2])
                self.wfile.flush()
                self.connection.shutdown(socket.SHUT_WR)
                return
            self.wfile.write(body)

    return Handler


@pytest.fixture(scope="module")
def fixture_bytes(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """The fixture match as xz, and the same match on de_mirage."""
    folder = tmp_path_factory.mktemp("matches")
    other = make_match()
    other["mapName"] = "de_mirage"
    return {
        "dust2": write_match(folder / "dust2.json.xz").read_bytes(),
        "mirage": write_match(folder / "mirage.json.xz", other).read_bytes(),
    }


@pytest.fixture
def site(fixture_bytes: dict[str, bytes]) -> Iterator[Site]:
    """A fresh server on a free loopback port with every case of the module docstring."""
    dust2 = fixture_bytes["dust2"]
    served = Site(
        files={
            f"lan/{LAN_ID}.json.xz": dust2,
            f"online/{ONLINE_ID}.json.xz": dust2,
            "lan/mirage.json.xz": fixture_bytes["mirage"],
            "lan/html.json.xz": b"<!DOCTYPE html><html><body>rate limited</body></html>",
            "lan/lfs.json.xz": b"version https://git-lfs.github.com/spec/v1\noid sha256:ab\n",
            "lan/corrupt.json.xz": dust2[: len(dust2) // 2],
            "lan/cut.json.xz": dust2,
            "lan/slow.json.xz": dust2,
        },
        behaviours={
            "lan/broken.json.xz": "error",
            "lan/cut.json.xz": "truncated",
            "lan/slow.json.xz": "slow",
        },
    )
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _handler(served))
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    served.base_url = f"http://127.0.0.1:{server.server_address[1]}"
    try:
        yield served
    finally:
        server.shutdown()
        server.server_close()


def _download(site: Site, dest: Path, *args: str):
    return runner.invoke(
        app, ["download", *args, "--dest", str(dest), "--base-url", site.base_url], env=WIDE
    )


def _leftovers(dest: Path) -> list[str]:
    return sorted(p.name for p in dest.iterdir() if p.name.startswith("."))


def test_default_base_url_is_the_esta_repository_raw_files() -> None:
    ref = parse_match_id(LAN_ID)
    assert match_urls(ref) == [
        f"https://raw.githubusercontent.com/pnxenopoulos/esta/main/data/{sub}/{LAN_ID}.json.xz"
        for sub in ("lan", "online")
    ]
    assert ESTA_BASE_URL.endswith("/pnxenopoulos/esta/main/data")
    named = parse_match_id(f"online/{ONLINE_ID}.json.xz")
    assert (named.name, named.subset) == (ONLINE_ID, "online")
    assert match_urls(named, "http://mirror/x/") == [f"http://mirror/x/online/{ONLINE_ID}.json.xz"]


@pytest.mark.parametrize("bad", ["../etc/passwd", "lan/", "a b", "cs/x", "", "x" * 200])
def test_bad_ids_are_refused(bad: str) -> None:
    with pytest.raises(DownloadError, match="not an ESTA match id"):
        parse_match_id(bad)


def test_downloads_verify_and_land_in_the_folder(site: Site, tmp_path: Path) -> None:
    dest = tmp_path / "esta"
    result = _download(site, dest, LAN_ID, ONLINE_ID)
    assert result.exit_code == 0, result.output
    for match_id in (LAN_ID, ONLINE_ID):
        path = dest / f"{match_id}.json.xz"
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert f"{match_id}: downloaded" in result.stdout
        assert f"sha256 {digest}" in result.stdout
        assert "3 rounds" in result.stdout
    assert f"lan/{ONLINE_ID}.json.xz" in site.requests  # a bare id tries lan/ first
    assert f"online/{ONLINE_ID}.json.xz" in site.requests
    assert _leftovers(dest) == []

    site.requests.clear()
    again = _download(site, dest, LAN_ID)
    assert again.exit_code == 0, again.output
    assert f"{LAN_ID}: already present" in again.stdout
    assert site.requests == []


def test_each_failure_is_one_line_and_the_others_go_on(site: Site, tmp_path: Path) -> None:
    dest = tmp_path / "esta"
    ids = ["missing", "broken", "cut", "mirage", "html", "lfs", "corrupt", LAN_ID, "../x"]
    result = _download(site, dest, *ids)
    assert result.exit_code == 1
    lines = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(lines) == len(ids) - 1, result.stderr
    by_id = {line.split()[1].rstrip(":"): line for line in lines}
    assert "not found (HTTP 404)" in by_id["missing"] and "online/missing" in by_id["missing"]
    assert "HTTP 503" in by_id["broken"]
    assert "cut short" in by_id["cut"]
    assert "de_mirage match, not de_dust2: not kept" in by_id["mirage"]
    assert "not xz data" in by_id["html"]
    assert "Git LFS pointer" in by_id["lfs"]
    assert "not a readable ESTA match" in by_id["corrupt"]
    assert "not an ESTA match id" in lines[-1]
    assert "8 of 9 ids failed" in result.stderr
    assert sorted(p.name for p in dest.iterdir()) == [f"{LAN_ID}.json.xz"]
    assert "Traceback" not in result.output


def test_another_map_is_kept_when_asked_for(site: Site, tmp_path: Path) -> None:
    dest = tmp_path / "esta"
    result = _download(site, dest, "mirage", LAN_ID, "--map", "mirage")
    assert result.exit_code == 1
    assert "de_dust2 match, not de_mirage: not kept" in result.stderr
    assert sorted(p.name for p in dest.iterdir()) == ["mirage.json.xz"]
    unknown = _download(site, dest, "mirage", "--map", "cache")
    assert unknown.exit_code == 1 and unknown.stderr.startswith("error: unknown map 'cache'")


def test_refused_connection_and_timeout(site: Site, tmp_path: Path) -> None:
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        closed = f"http://127.0.0.1:{probe.getsockname()[1]}"
    refused = runner.invoke(
        app, ["download", LAN_ID, "--dest", str(tmp_path), "--base-url", closed], env=WIDE
    )
    assert refused.exit_code == 1
    assert f"error: {LAN_ID}: cannot reach 127.0.0.1" in refused.stderr

    slow = _download(site, tmp_path, "slow", "--timeout", "0.3")
    assert slow.exit_code == 1
    assert "error: slow: no answer from" in slow.stderr and "within 0.3 s" in slow.stderr
    assert list(tmp_path.iterdir()) == []


def test_sha256_is_checked(site: Site, fixture_bytes: dict[str, bytes], tmp_path: Path) -> None:
    good = hashlib.sha256(fixture_bytes["dust2"]).hexdigest()
    bad = "0" * 64
    result = _download(
        site,
        tmp_path,
        LAN_ID,
        ONLINE_ID,
        "--sha256",
        f"{LAN_ID}={good.upper()}",
        "--sha256",
        f"{ONLINE_ID}={bad}",
    )
    assert result.exit_code == 1
    assert f"{LAN_ID}: downloaded" in result.stdout
    assert f"sha256 mismatch: expected {bad}, got {good}" in result.stderr
    assert not (tmp_path / f"{ONLINE_ID}.json.xz").exists()

    for option, message in (
        (f"{LAN_ID}=xyz", "is not a sha256"),
        ("nohex", "expected ID=HEX"),
        (f"other={good}", "not among the ids"),
    ):
        refused = _download(site, tmp_path, LAN_ID, "--sha256", option)
        assert refused.exit_code == 1
        assert message in refused.stderr


def test_a_bad_file_in_place_is_replaced(site: Site, tmp_path: Path) -> None:
    target = tmp_path / f"{LAN_ID}.json.xz"
    target.write_bytes(lzma.compress(b'{"gameRounds": "no"}'))
    result = _download(site, tmp_path, LAN_ID)
    assert result.exit_code == 0, result.output
    assert f"{LAN_ID}: replaced" in result.stdout and "failed verification" in result.stdout
    assert verify_file(target)[1] == 3


def test_a_file_url_mirror_and_the_library_call(
    fixture_bytes: dict[str, bytes], tmp_path: Path
) -> None:
    mirror = tmp_path / "mirror"
    (mirror / "online").mkdir(parents=True)
    (mirror / "online" / f"{ONLINE_ID}.json.xz").write_bytes(fixture_bytes["dust2"])
    seen: list[tuple[int, int | None]] = []
    result = download_match(
        ONLINE_ID,
        tmp_path / "out",
        base_url=mirror.as_uri(),
        on_progress=lambda done, total: seen.append((done, total)),
    )
    assert result.status == "downloaded" and result.rounds == 3
    assert result.url == f"{mirror.as_uri()}/online/{ONLINE_ID}.json.xz"
    assert seen[-1] == (len(fixture_bytes["dust2"]), len(fixture_bytes["dust2"]))
    with pytest.raises(DownloadError, match=r"^nope: not found \(HTTP 404\)"):
        download_match("nope", tmp_path / "out", base_url=mirror.as_uri())
