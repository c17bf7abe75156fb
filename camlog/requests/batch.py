"""``camlog batch``'s request: the pipeline file, the logs, where outputs go, and where the
logs run (local processes or Ray)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from replay.storage import Location

from . import fields as common
from .fields import RequestError, option, required
from .values import bounded_int, positive

__all__ = ["DEFAULT_JOBS", "ENGINES", "BatchRequest"]

#: where the logs run: local processes or a Ray cluster
ENGINES = ("process", "ray")
#: logs processed at once by default (on an existing Ray cluster: as many as its CPUs hold)
DEFAULT_JOBS = 2


@dataclass(frozen=True, kw_only=True)
class BatchRequest:
    """Run a pipeline (resync, calibrate, process, ...) over many logs in parallel."""

    epilog: ClassVar[str] = (
        "PIPELINE is a .toml or .yaml file with [[steps]] tables; step kinds: resync, "
        "calibrate, process, throttle, info, check, convert, export. LOG and OUTDIR are paths "
        "or URIs (file://, s3://, gs://, ...; a quoted URI pattern such as "
        "'s3://bucket/logs/*.mcap' is expanded). Each log's outputs go to OUTDIR/<log "
        "name>/NN_<step>/; logs whose outputs are complete for the same input and pipeline "
        "are skipped. The exit status is 1 when any log failed."
    )

    pipeline: Path = required(metavar="PIPELINE", type=Path, batch=False,
                              help="pipeline file")
    logs: tuple[Location, ...] = option((), metavar="LOG", nargs="+", batch=False,
                                        help="input logs (paths or URIs)")
    jobs: int | None = option(
        None, "-j", "--jobs", type=int, metavar="N", batch=False,
        help="logs processed at once (default 2; on an existing Ray cluster, as many as its "
             "CPUs hold)")
    output: Location = option("batch_out", "-o", "--output", metavar="OUTDIR", batch=False,
                              help="output folder or URI (default batch_out)")
    engine: str = option("process", "--engine", choices=ENGINES, batch=False,
                         help="local processes (default) or Ray (pip install 'camlog[ray]')")
    address: str | None = option(
        None, "--address", metavar="HOST:PORT", batch=False,
        help="an existing Ray cluster, or 'auto' (default: RAY_ADDRESS; without either, "
             "--engine ray starts a local instance)")
    cpus_per_log: float = option(1.0, "--cpus-per-log", type=positive, metavar="N",
                                 batch=False,
                                 help="CPUs each log's task asks of Ray (default 1)")
    retries: int = option(2, "--retries", type=bounded_int(0, None), metavar="N", batch=False,
                          help="runs again a log whose worker or node died, up to N times "
                               "(default 2)")
    progress: bool | None = common.progress()

    def __post_init__(self) -> None:
        if self.jobs is not None and self.jobs < 1:
            raise RequestError(BatchRequest, f"{{jobs}} must be at least 1, got {self.jobs}")
        if self.engine not in ENGINES:
            raise RequestError(BatchRequest, f"unknown {{engine}} {self.engine!r} (use "
                                             f"{' or '.join(ENGINES)})")
        if not self.cpus_per_log > 0:
            raise RequestError(BatchRequest, f"{{cpus_per_log}} must be positive, got "
                                             f"{self.cpus_per_log}")
        if self.retries < 0:
            raise RequestError(BatchRequest, f"{{retries}} must be 0 or more, got "
                                             f"{self.retries}")
        if self.address is not None and self.engine != "ray":
            raise RequestError(BatchRequest, "{address} needs {engine} ray")
