"""The resumable store of finished tasks and the rules for outputs (refuse, resume, overwrite).
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from .. import io
from ..errors import FieldError, OutputExistsError, WaveopticsError

__all__ = ['partial_path', 'check_resume_overwrite']

def check_resume_overwrite(resume: bool, overwrite: bool) -> None:
    """*resume* keeps the finished tasks of an interrupted run, *overwrite* discards them: asking for both is a
    contradiction, refused in one line (neither wins silently)."""
    if resume and overwrite:
        raise FieldError("{resume} continues the interrupted run and {overwrite} discards it; give one of them",
                         "resume", "overwrite", python={"overwrite": "overwrite=True", "resume": "resume=True"})


def refuse_or_prepare(final: Path, partial: Path, *, resume: bool, overwrite: bool) -> None:
    """Apply the rules on existing outputs before any work (see :func:`run_table`)."""
    check_resume_overwrite(resume, overwrite)
    parent = final.parent if str(final.parent) else Path(".")
    if not parent.is_dir():
        raise WaveopticsError(f"output directory {str(parent)!r} does not exist")
    if final.exists() and not overwrite and not resume:
        raise OutputExistsError(final)
    if partial.exists() and not any((partial / "items").glob("[!.]*")):
        shutil.rmtree(partial)  # a run that stopped before its first result: nothing to resume
    if partial.exists() and not resume:
        if not overwrite:
            raise OutputExistsError(partial, "{path} holds an interrupted run; pass {resume} to continue it or "
                                             "{overwrite} to start over")
        shutil.rmtree(partial)


class Store:
    """The partial store ``OUT.partial/``: ``run.json`` (parameters) and one atomically written file per task."""

    def __init__(self, root: Path, run: dict, *, resume: bool):
        self.root = Path(root)
        self.items = self.root / "items"
        meta = self.root / "run.json"
        if self.root.exists():
            try:
                old = json.loads(meta.read_text())
            except (OSError, ValueError):
                raise FieldError(f"{str(self.root)!r} is not a waveoptics partial run (no readable run.json); "
                                 "remove it or pass {overwrite}", "overwrite",
                                 python={"overwrite": "overwrite=True"}) from None
            if old.get("token") != run["token"]:
                diff = [k for k in sorted(set(old.get("parameters", {})) | set(run["parameters"]))
                        if old.get("parameters", {}).get(k) != run["parameters"].get(k)]
                raise FieldError(f"{{resume}}: {str(self.root)!r} was started with different parameters "
                                 f"({', '.join(diff) or 'surface'}); pass {{overwrite}} to start over", "resume",
                                 "overwrite", python={"overwrite": "overwrite=True", "resume": "resume=True"})
        else:
            self.items.mkdir(parents=True)
            io.write_json(meta, run)
        self.items.mkdir(exist_ok=True)

    def path(self, name: str, suffix: str) -> Path:
        return self.items / f"{name}{suffix}"

    def has(self, name: str, suffix: str) -> bool:
        return self.path(name, suffix).is_file()

    def remove(self) -> None:
        shutil.rmtree(self.root)


def partial_path(output) -> Path:
    """The partial store of an output: ``OUT.partial`` (a directory)."""
    p = Path(output)
    return p.with_name(p.name + ".partial")
