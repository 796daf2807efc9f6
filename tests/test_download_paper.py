"""`decoy models download-decoy` against a local server laid out as the paper's repository
(files made here, not the real weights), and the recorded checksums against the published files."""

from __future__ import annotations

import hashlib
import http.server
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
import torch
from test_damage_import import PUBLISHED, random_state, write_paper_folder
from test_download import Site, _handler
from typer.testing import CliRunner

import decoy_cli.modeling.paper_download as download_paper
from decoy_cli.cli import app
from decoy_cli.damage.model_folder import load_dip, load_dog
from decoy_cli.damage.networks import DipNet, DogNet
from decoy_cli.modeling.paper_download import PAPER_FILES, PaperFile

runner = CliRunner()
WIDE = {"COLUMNS": "200"}


@pytest.fixture
def repository(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Site]:
    """A server with the four files at the paper's paths; PAPER_FILES records their hashes."""
    made = write_paper_folder(
        tmp_path / "made", random_state(DipNet(), 3), random_state(DogNet(), 4)
    )
    files, recorded = {}, {}
    for name, published in PAPER_FILES.items():
        body = (made / name).read_bytes()
        files[published.path] = body
        recorded[name] = PaperFile(published.path, hashlib.sha256(body).hexdigest(), len(body))
    monkeypatch.setattr(download_paper, "PAPER_FILES", recorded)
    site = Site(files=files)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _handler(site))
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    site.base_url = f"http://127.0.0.1:{server.server_address[1]}"
    try:
        yield site
    finally:
        server.shutdown()
        server.server_close()


def run(site_url: str, out: Path):
    args = ["models", "download-decoy", "--out", str(out), "--base-url", site_url]
    return runner.invoke(app, [*args, "--timeout", "5"], env=WIDE)


def test_download_verifies_and_imports(repository: Site, tmp_path: Path) -> None:
    out = tmp_path / "paper"
    result = run(repository.base_url, out)
    assert result.exit_code == 0, result.output
    assert "4 files of HATS-ICT/decoy@6f93b8e verified" in result.output
    assert load_dip(out).threshold == pytest.approx(0.444)
    load_dog(out)
    assert sorted(p.name for p in (out / "checkpoints").iterdir()) == sorted(PAPER_FILES)
    asked = len(repository.requests)
    assert run(repository.base_url, out).exit_code == 0  # verified files are kept
    assert len(repository.requests) == asked


def test_a_wrong_checksum_or_a_cut_download_imports_nothing(
    repository: Site, tmp_path: Path
) -> None:
    path = PAPER_FILES["dog_best_model.pth"].path
    body = repository.files[path]
    repository.files[path] = body[:-10] + b"0123456789"  # same size, other bytes
    result = run(repository.base_url, tmp_path / "a")
    assert result.exit_code == 1 and "not the published file" in result.output
    assert not (tmp_path / "a" / "dog.json").exists()
    assert not list((tmp_path / "a" / "checkpoints").glob("*.part"))
    repository.files[path] = body
    repository.behaviours[path] = "truncated"
    result = run(repository.base_url, tmp_path / "b")
    assert result.exit_code == 1 and "cut short" in result.output
    assert not (tmp_path / "b" / "dog.json").exists()
    assert not list((tmp_path / "b" / "checkpoints").glob("*.part"))
    assert "Traceback" not in result.output


def test_no_network_is_one_line(tmp_path: Path) -> None:
    result = run("http://127.0.0.1:9", tmp_path / "paper")  # nothing listens on port 9
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert not (tmp_path / "paper").exists()  # no empty folders left behind
    assert "error: dip_best_model.pth: cannot reach 127.0.0.1:9" in result.output


@pytest.mark.skipif(not PUBLISHED.is_dir(), reason="needs ../shared/data/decoy_checkpoints")
def test_the_recorded_checksums_are_the_published_files() -> None:
    for name, published in download_paper.PAPER_FILES.items():
        data = (PUBLISHED / name).read_bytes()
        assert hashlib.sha256(data).hexdigest() == published.sha256, name
        assert len(data) == published.size, name
    checkpoint = torch.load(PUBLISHED / "dip_best_model.pth", map_location="cpu", weights_only=True)
    assert "model_state_dict" in checkpoint
