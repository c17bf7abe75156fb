"""Bring every corpus dataset into a cache outside the repository, checked by sha256.

Each repository is read at its pinned commit: fetched over https into a bare clone in
``CACHE/git`` or, when that fails, read from a local bare mirror under ``--mirror-root``
(``ROOT/owner+name/repo`` or ``ROOT/owner+name/repo/.git``). Each dataset becomes
``CACHE/NAME/`` holding its images only (a pair as ``left*`` / ``right*``), ready for
``camlog import``.

    python -m benchmarks.corpus.fetch [--cache DIR] [--mirror-root DIR] [--only NAME…]
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
from pathlib import Path

from .manifest import CorpusError, Dataset, default_cache, load_manifest

GIT_TIMEOUT_S = 600


def _git(*args: str, timeout_s: float = GIT_TIMEOUT_S) -> subprocess.CompletedProcess[bytes]:
    env = os.environ | {"GIT_TERMINAL_PROMPT": "0"}
    return subprocess.run(["git", *args], capture_output=True, timeout=timeout_s, env=env,
                          check=False)


def _has_commit(git_dir: Path, commit: str) -> bool:
    return git_dir.is_dir() and _git(f"--git-dir={git_dir}", "cat-file", "-e",
                                     f"{commit}^{{commit}}").returncode == 0


def _mirror(mirror_root: Path, repo: str) -> Path | None:
    base = mirror_root / repo.replace("/", "+") / "repo"
    for candidate in (base / ".git", base):
        if (candidate / "objects").is_dir():
            return candidate
    return None


def git_source(dataset: Dataset, cache: Path, mirror_root: Path | None) -> tuple[Path, str]:
    """A git directory holding ``dataset.commit``, and where it came from."""
    clone = cache / "git" / (dataset.repo.replace("/", "+") + ".git")
    if _has_commit(clone, dataset.commit):
        return clone, f"{dataset.url} (cached clone)"
    if not clone.is_dir():
        _git("init", "--bare", "--quiet", str(clone))
    fetched = _git(f"--git-dir={clone}", "fetch", "--quiet", "--depth", "1", dataset.url,
                   dataset.commit)
    if fetched.returncode == 0 and _has_commit(clone, dataset.commit):
        return clone, dataset.url
    https_error = fetched.stderr.decode(errors="replace").strip().splitlines()[-1:] or ["?"]
    mirror = _mirror(mirror_root, dataset.repo) if mirror_root else None
    if mirror is not None and _has_commit(mirror, dataset.commit):
        return mirror, f"mirror {mirror}"
    where = f"; no mirror of it holds that commit under {mirror_root}" if mirror_root else ""
    raise CorpusError(f"{dataset.name}: {dataset.url} @ {dataset.commit[:12]} not reachable "
                      f"({https_error[0]}){where}")


def fetch_dataset(dataset: Dataset, cache: Path, mirror_root: Path | None) -> str:
    """Write ``cache/NAME/`` from the pinned commit, every file checked; return the source."""
    folder = cache / dataset.name
    if folder.is_dir() and all(_sha256(folder / Path(f).name) == h
                               for f, h in dataset.files.items()):
        return "cache"
    git_dir, source = git_source(dataset, cache, mirror_root)
    folder.mkdir(parents=True, exist_ok=True)
    for relative, expected in dataset.files.items():
        blob = _git(f"--git-dir={git_dir}", "show", f"{dataset.commit}:{dataset.path}/{relative}")
        if blob.returncode != 0:
            raise CorpusError(f"{dataset.name}: {dataset.path}/{relative} is not in "
                              f"{dataset.repo} @ {dataset.commit[:12]}")
        got = hashlib.sha256(blob.stdout).hexdigest()
        if got != expected:
            raise CorpusError(f"{dataset.name}: {relative} has sha256 {got}, the manifest "
                              f"says {expected}")
        target = folder / Path(relative).name
        target.with_suffix(target.suffix + ".part").write_bytes(blob.stdout)
        target.with_suffix(target.suffix + ".part").replace(target)
    return source


def _sha256(path: Path) -> str | None:
    return hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None


def fetch_all(cache: Path, mirror_root: Path | None, only: list[str] | None = None) -> int:
    """Fetch each dataset (or those named), printing one line each; 1 if any failed."""
    failed = 0
    for dataset in load_manifest():
        if only and dataset.name not in only:
            continue
        try:
            source = fetch_dataset(dataset, cache, mirror_root)
        except (CorpusError, subprocess.TimeoutExpired) as error:
            print(f"{dataset.name}: FAILED: {error}", file=sys.stderr)
            failed = 1
            continue
        print(f"{dataset.name}: {len(dataset.files)} files in {cache / dataset.name} "
              f"from {source}")
    return failed


def main() -> int:
    """Parse the command line and fetch."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cache", type=Path, default=default_cache(),
                        help="cache folder (default $CAMLOG_CORPUS or ~/.cache/camlog/corpus)")
    parser.add_argument("--mirror-root", type=Path,
                        help="folder of local bare mirrors, owner+name/repo, used when https "
                             "is not reachable")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="fetch only these datasets")
    args = parser.parse_args()
    return fetch_all(args.cache, args.mirror_root, args.only)


if __name__ == "__main__":
    sys.exit(main())
