"""A small per-user cache for what is measured once per machine: the planner's cost-model calibration and the
plans it made, so that ``waveoptics plan`` answers without timing runs (and, for a scene it has planned before,
without importing the numerical libraries).

Location: ``$WAVEOPTICS_CACHE_DIR``, else ``$XDG_CACHE_HOME/waveoptics``, else ``~/.cache/waveoptics``. Entries
are keyed by the machine (:func:`machine_key`: CPU model and count, worker threads, Python, NumPy and waveoptics
versions), so a cache copied to another machine, or kept across an upgrade, is not used there. A plan entry is
also keyed by the scene file's bytes, the bytes of every file the scene names, and the options. Writes are atomic;
a cache that cannot be written (read-only home) is skipped without a word, since it only saves time. This module
imports nothing heavy.

Arrays (:func:`get_arrays`, :func:`put_arrays`: the tabulated lobes of the models handed to renderers) are kept one
``.npz`` file per key under ``arrays/KIND/``; their keys hold every parameter of what was computed and
:func:`code_version` (the package's version and the bytes of its source), not the machine: the numbers do not
depend on it.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import tempfile
from pathlib import Path

__all__ = ["cache_dir", "machine_key", "get", "put", "file_digest", "code_version", "key_digest", "get_arrays",
           "put_arrays"]

#: bump when the layout of an entry changes
FORMAT = 1


def cache_dir() -> Path:
    """The cache directory (not created here)."""
    if os.environ.get("WAVEOPTICS_CACHE_DIR"):
        return Path(os.environ["WAVEOPTICS_CACHE_DIR"]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "waveoptics"


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _version(dist: str) -> str:
    from importlib import metadata

    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "none"


def machine_key() -> str:
    """What a timing measured here depends on: CPU model and count, the worker threads waveoptics may use
    (``WAVEOPTICS_WORKERS``), Python, NumPy and waveoptics versions."""
    parts = [_cpu_model(), str(os.cpu_count()), os.environ.get("WAVEOPTICS_WORKERS", ""),
             platform.python_version(), _version("numpy"), _version("waveoptics"), f"format {FORMAT}"]
    return hashlib.sha256("|".join(parts).encode()).hexdigest()[:20]


def file_digest(path) -> str:
    """SHA-256 of a file's bytes ("missing" when it cannot be read)."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return "missing"
    return h.hexdigest()


def _path(kind: str) -> Path:
    return cache_dir() / f"{kind}-{machine_key()}.json"


def get(kind: str, key: str):
    """The value stored under *key* in the *kind* cache of this machine, or None."""
    try:
        data = json.loads(_path(kind).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data.get(key) if isinstance(data, dict) else None


def put(kind: str, key: str, value, *, keep: int = 64) -> None:
    """Store *value* (plain JSON data) under *key*; keeps the *keep* newest keys of the kind."""
    path = _path(kind)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict):
            data = {}
    except (OSError, ValueError):
        data = {}
    data.pop(key, None)
    data[key] = value
    while len(data) > keep:
        data.pop(next(iter(data)))
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(data, fh)
        os.replace(tmp, path)
    except OSError:
        pass   # a cache only saves time: an unwritable one is skipped


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """The waveoptics version, NumPy's and SciPy's, and a SHA-256 of the bytes of every ``.py`` file of the
    package: a computed array depends on the code that computed it, which an editable install changes without a
    new version. Computed once per process (~15 ms: the code a process runs is the code it imported)."""
    h = hashlib.sha256()
    root = Path(__file__).resolve().parent
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(file_digest(path).encode())
    return "|".join([_version("waveoptics"), _version("numpy"), _version("scipy"), h.hexdigest()[:20]])


def key_digest(parts: dict) -> str:
    """A file-name-safe digest of *parts* (plain JSON data: every parameter of a computation) and
    :func:`code_version`."""
    text = json.dumps({"parts": parts, "code": code_version(), "format": FORMAT}, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _array_path(kind: str, digest: str) -> Path:
    return cache_dir() / "arrays" / kind / f"{digest}.npz"


def get_arrays(kind: str, digest: str):
    """The arrays stored under *digest* (:func:`key_digest`) in the *kind* cache, as a dict, or None."""
    import numpy as np

    path = _array_path(kind, digest)
    try:
        with np.load(path, allow_pickle=False) as data:
            out = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError):
        return None
    try:
        os.utime(path)   # recently used: kept longest
    except OSError:
        pass
    return out


def put_arrays(kind: str, digest: str, arrays: dict, *, keep: int = 8) -> None:
    """Store *arrays* (name → ndarray) under *digest*; keeps the *keep* most recently used entries of the kind."""
    import numpy as np

    path = _array_path(kind, digest)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".npz", dir=path.parent)
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
        tmp = None
        entries = sorted(path.parent.glob("*.npz"), key=lambda p: p.stat().st_mtime, reverse=True)
        for old in entries[keep:]:
            old.unlink(missing_ok=True)
    except OSError:
        pass   # a cache only saves time: an unwritable one (or a full disk) is skipped
    finally:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
