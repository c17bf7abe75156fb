"""camlog batch with inputs and outputs on S3: a moto server on 127.0.0.1, started here."""

from __future__ import annotations

import io
import json
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import boto3
import pytest
from mcap.reader import make_reader

from camlog.cli import main
from tests.slow import renders

from .test_run import PIPELINE, SCENARIOS

BUCKET = "camlogs"


def free_port() -> int:
    """A TCP port nobody listens on (on 127.0.0.1)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
@renders
def s3_endpoint() -> Iterator[str]:
    """A moto S3 server bound to 127.0.0.1 for this module."""
    port = free_port()
    server = subprocess.Popen(
        [str(Path(sys.executable).parent / "moto_server"), "-H", "127.0.0.1", "-p", str(port)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), 0.5).close()
                break
            except OSError:
                assert server.poll() is None and time.monotonic() < deadline, \
                    "moto_server did not start"
                time.sleep(0.2)
        yield f"http://127.0.0.1:{port}"
    finally:
        server.terminate()
        server.wait(10)


@pytest.fixture
def s3(s3_endpoint: str, monkeypatch: pytest.MonkeyPatch) -> object:
    """An S3 client (boto3, independent of camlog) and the environment camlog reads."""
    for name, value in {"AWS_ACCESS_KEY_ID": "testing", "AWS_SECRET_ACCESS_KEY": "testing",
                        "AWS_DEFAULT_REGION": "us-east-1",
                        "AWS_ENDPOINT_URL": s3_endpoint}.items():
        monkeypatch.setenv(name, value)
    import fsspec

    fsspec.filesystem("s3").clear_instance_cache()
    client = boto3.client("s3", endpoint_url=s3_endpoint)
    if BUCKET not in [b["Name"] for b in client.list_buckets()["Buckets"]]:
        client.create_bucket(Bucket=BUCKET)
    return client


@pytest.mark.slow
def test_batch_reads_and_writes_s3_uris(s3: object, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    client: object = s3
    for seed in (1, 2):
        log = tmp_path / f"cam{seed}.mcap"
        assert main(["record", str(SCENARIOS / "stereo_unsynced.toml"), "-o", str(log),
                     "--frames", "20", "--resolution", "160x120", "--seed", str(seed),
                     "--no-progress"]) == 0
        client.upload_file(str(log), BUCKET, f"logs/{log.name}")  # type: ignore[attr-defined]
    bag = tmp_path / "cam3.bag"  # another format: read from a temporary download
    assert main(["convert", str(tmp_path / "cam1.mcap"), str(bag)]) == 0
    client.upload_file(str(bag), BUCKET, "logs/cam3.bag")  # type: ignore[attr-defined]
    pipeline = tmp_path / "pipe.toml"
    pipeline.write_text(PIPELINE)
    out = f"s3://{BUCKET}/out"
    argv = ["batch", str(pipeline), f"s3://{BUCKET}/logs/*", "-o", out, "-j", "2",
            "--no-progress"]

    assert main(argv) == 0
    table = capsys.readouterr().out
    assert "3 of 3 logs done (0 failed)" in table, table

    def get(key: str) -> bytes:
        body = client.get_object(Bucket=BUCKET, Key=key)["Body"]  # type: ignore[attr-defined]
        return bytes(body.read())

    summary = json.loads(get("out/batch_summary.json"))
    statuses = {s["log"]: s for s in summary["logs"]}
    assert sorted(statuses) == [f"s3://{BUCKET}/logs/cam{i}.{ext}"
                                for i, ext in ((1, "mcap"), (2, "mcap"), (3, "bag"))]
    for name in ("cam1", "cam2", "cam3"):
        status = json.loads(get(f"out/{name}/batch_status.json"))
        assert status["status"] == "ok" and status["input"]["etag"]
        processed = status["steps"][1]["files"][0]
        assert processed == f"{out}/{name}/02_process/processed.mcap"
        data = get(f"out/{name}/02_process/processed.mcap")
        reader = make_reader(io.BytesIO(data))  # mcap's own reader
        edges = [m for _, c, m in reader.iter_messages() if c.topic.endswith("/edges")]
        assert len(edges) == status["steps"][1]["figures"]["frames"] > 10
    assert "notes" not in statuses[f"s3://{BUCKET}/logs/cam1.mcap"]  # MCAP read in place
    assert "downloaded" in statuses[f"s3://{BUCKET}/logs/cam3.bag"]["notes"][0]
    info = get("out/cam3/03_info/info.txt").decode()
    assert "/stereo_sync/left/image_raw" in info

    # a second run skips everything; a missing output object redoes its log only
    assert main(argv) == 0
    assert capsys.readouterr().out.count(" skipped ") == 3
    client.delete_object(Bucket=BUCKET,  # type: ignore[attr-defined]
                         Key="out/cam2/02_process/processed.mcap")
    assert main(argv) == 0
    rows = {line.split()[0]: line.split()[1] for line in capsys.readouterr().out.splitlines()
            if line.startswith("cam")}
    assert rows == {"cam1.mcap": "skipped", "cam2.mcap": "ok", "cam3.bag": "skipped"}


def test_an_unreachable_bucket_is_one_line(s3: object, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    pipeline = tmp_path / "pipe.toml"
    pipeline.write_text(PIPELINE)
    assert main(["batch", str(pipeline), "s3://no-such-bucket/logs/*.mcap", "-o",
                 str(tmp_path / "o"), "--no-progress"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("camlog batch: error:"), err
    assert "no-such-bucket" in err[0]
