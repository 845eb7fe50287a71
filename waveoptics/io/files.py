"""File output that never leaves a half-written file under a final name, plus JSON and OpenEXR helpers.

Every writer goes through :func:`atomic_path`: the data is written to a temporary name in the same
directory and moved into place with :func:`os.replace` only when complete, so an interrupted or failed
run leaves the previous result (if any) untouched. Sets of files (a run's EXRs, figures and summary) go through
:func:`staged_outputs`: staged whole, then moved under a journal with the manifest last, so a killed run leaves
the earlier set, or a directory without a manifest whose journal the next run replays (:func:`recover_staged`).
"""
from __future__ import annotations

import contextlib
import fcntl
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import OpenEXR

from ..errors import OutputExistsError, WaveopticsError

__all__ = ['NonFiniteOutputError', 'atomic_path', 'staged_outputs', 'recover_staged', 'prepare_outdir', 'to_json', 'write_json', 'write_exr', 'write_rgb_exr', 'gamut_note', 'read_exr']

@contextlib.contextmanager
def atomic_path(final, *, overwrite: bool = True):
    """Yield a temporary path next to *final*; on success it is renamed to *final*.

    Parameters
    ----------
    final : str or Path
        The destination file.
    overwrite : bool
        When False and *final* exists, raise :class:`OutputExistsError` before writing anything.
    """
    final = Path(final)
    if final.exists() and not overwrite:
        raise OutputExistsError(final)
    parent = final.parent if str(final.parent) else Path(".")
    if not parent.is_dir():
        raise WaveopticsError(f"output directory {str(parent)!r} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=f".partial{final.suffix}", dir=parent)
    except OSError as exc:
        raise WaveopticsError(f"cannot write {str(final)!r}: {exc.strerror or exc}") from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())   # mkstemp makes 0600; the result honours the umask like open() would
        os.replace(tmp, final)
    except OSError as exc:   # a full disk, a vanished directory, a permission: one line naming the output
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise WaveopticsError(f"cannot write {str(final)!r}: {exc.strerror or exc}") from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


#: a staging directory's journal: written (and flushed to disk) once the new set is whole, before the first move
JOURNAL = "journal.json"
#: held (flock) by the process that stages a set, for as long as it runs; the kernel drops it when that process dies
LOCK = "lock"
#: a staging directory without a lock file younger than this (s) may still be starting up
_YOUNG_S = 60.0


def _stage_dirs(directory: Path):
    try:
        return sorted(p for p in directory.glob(".staging.*.partial") if p.is_dir())
    except OSError:
        return []


def _owner_alive(stage: Path) -> bool:
    """Whether the process that created *stage* still holds its lock (it is then still writing or committing)."""
    lock = stage / LOCK
    try:
        fd = os.open(lock, os.O_RDWR)
    except FileNotFoundError:   # killed before it took the lock, or still starting: judge by age
        try:
            return time.time() - stage.stat().st_mtime < _YOUNG_S
        except OSError:
            return False
    except OSError:
        return True             # cannot tell: leave it alone
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def _commit(stage: Path, directory: Path, order: list[str], stale=()) -> None:
    """Move the staged set *order* (manifest last) into *directory*.

    The manifest (the last name, e.g. summary.json) of the earlier set is removed first: from that moment until the
    new manifest lands, the directory holds no manifest, i.e. no complete set, instead of a mix that looks whole.
    Then the earlier set's members that the new set does not hold (*stale*) are removed, so the directory never
    shows files of another run beside the new manifest. Files already moved or removed (a commit resumed after a
    kill) are skipped, so the commit can be replayed."""
    for n in (order[-1], *stale):
        with contextlib.suppress(FileNotFoundError):
            os.unlink(directory / n)
    for n in order:
        if (stage / n).is_file():
            try:
                os.replace(stage / n, directory / n)
            except OSError as exc:
                raise WaveopticsError(f"cannot write {str(directory / n)!r}: {exc.strerror or exc}") from None


def recover_staged(directory) -> list[str]:
    """Finish or clear what killed runs left in *directory*.

    A staging directory whose owner is dead is either *journalled* (its set was whole and the commit had begun: the
    commit is replayed, so the new set lands whole) or not (the run died while computing or writing: it is removed,
    and the earlier set was never touched). Staging directories of live runs are left alone. Called before every
    staged write and by :func:`prepare_outdir`; returns what it did, one line per staging directory.
    """
    directory = Path(directory)
    done = []
    for stage in _stage_dirs(directory):
        if _owner_alive(stage):
            continue
        journal = stage / JOURNAL
        try:
            record = json.loads(journal.read_text()) if journal.is_file() else {}
            order, stale = record.get("order"), record.get("stale", [])
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            order = None   # a journal cut short by the kill: its set had not started moving
        if order:
            _commit(stage, directory, [str(n) for n in order], [str(n) for n in stale])
            done.append(f"completed the interrupted output set of {str(stage)!r}")
        else:
            done.append(f"removed the unfinished output set {str(stage)!r}")
        shutil.rmtree(stage, ignore_errors=True)
    return done


@contextlib.contextmanager
def staged_outputs(directory, names, *, last=None, members=()):
    """Write a set of output files as a whole: yield a hidden staging directory inside *directory*; when the block
    succeeds, every file in *names* is moved from it into *directory* (*last*, the set's manifest such as
    summary.json, after the others); when it fails or is interrupted, the staging directory is removed and
    *directory* is as it was. *members*: every file a set of this kind may hold; those not in *names* (an earlier
    run's optional outputs, e.g. sphere renders this run skipped) are removed when the new set lands.

    A kill (SIGKILL, power loss) cannot leave a mix that looks whole:

    * before the set is whole, the earlier set is untouched; the next run into *directory* removes the litter;
    * once it is whole, a journal listing the moves is written and flushed, the earlier manifest is removed, the
      files are moved and the new manifest comes last. A kill between two moves leaves a directory *without a
      manifest* (readers treat it as incomplete) and the journal; the next run into *directory*
      (:func:`recover_staged`) replays the moves, so the new set lands whole.

    The staging directory holds a lock for as long as its run lives, so concurrent runs never clear each other's.
    """
    directory = Path(directory)
    recover_staged(directory)
    stage = None
    try:
        stage = Path(tempfile.mkdtemp(prefix=".staging.", suffix=".partial", dir=directory))
        lock_fd = os.open(stage / LOCK, os.O_RDWR | os.O_CREAT, 0o600)
    except OSError as exc:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        raise WaveopticsError(f"cannot write into {str(directory)!r}: {exc.strerror or exc}") from None
    try:
        fcntl.flock(lock_fd, fcntl.LOCK_EX)
        yield stage
        names = list(names)
        last = last if last is not None else names[-1]
        order = [n for n in names if n != last] + [last]
        missing = [n for n in order if not (stage / n).is_file()]
        if missing:
            raise WaveopticsError(f"output set in {str(directory)!r} is incomplete: {', '.join(missing)} missing")
        stale = [str(n) for n in members if n not in order]
        try:
            with open(stage / (JOURNAL + ".tmp"), "w") as fh:
                json.dump({"order": order, "stale": stale}, fh)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(stage / (JOURNAL + ".tmp"), stage / JOURNAL)
        except OSError as exc:
            raise WaveopticsError(f"cannot write into {str(directory)!r}: {exc.strerror or exc}") from None
        _commit(stage, directory, order, stale)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        os.close(lock_fd)


def _umask() -> int:
    """The process umask (read by setting and restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def prepare_outdir(path, *, overwrite: bool = False, expected=()) -> Path:
    """Create output directory *path* (with parents) and check it is writable.

    Parameters
    ----------
    expected : iterable of str
        File names the run will write; if any exists and *overwrite* is False, refuse before computing.
    """
    if not str(path).strip():
        raise WaveopticsError("output directory '' is empty; give a directory name (e.g. -o out/)")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise WaveopticsError(f"output directory {str(p)!r} is a file, not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WaveopticsError(f"cannot create output directory {str(p)!r}: {exc.strerror}") from None
    if not os.access(p, os.W_OK | os.X_OK):
        raise WaveopticsError(f"output directory {str(p)!r} is not writable")
    recover_staged(p)   # a set a killed run was moving into place lands whole before anything checks for it
    if not overwrite:
        clash = [name for name in expected if (p / name).exists()]
        if clash:
            raise OutputExistsError(p / clash[0])
    return p


class NonFiniteOutputError(WaveopticsError):
    """A number about to leave a command is NaN or infinite: an error naming where, never an output."""


def _jsonable(obj, where="", strict=True):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v, f"{where}.{k}" if where else str(k), strict) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v, f"{where}[{i}]", strict) for i, v in enumerate(obj)]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist(), where, strict)
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        if np.isfinite(v):
            return v
        if strict:
            raise NonFiniteOutputError(f"the result {where or 'value'} is {v} (a computation left the range of "
                                       "double precision or divided 0 by 0)")
        return None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, Path):
        return str(obj)
    return obj


def to_json(data, *, strict: bool = True, **kw) -> str:
    """JSON text of *data*, converting numpy types. A NaN or infinite number raises
    :class:`NonFiniteOutputError` naming its place (*strict*, the default: every number leaving a command is
    finite), or becomes ``null`` with ``strict=False``."""
    return json.dumps(_jsonable(data, strict=strict), **kw)


def write_json(path, data, *, overwrite: bool = True) -> Path:
    """Write *data* as indented JSON atomically."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(to_json(data, indent=2) + "\n")
    return Path(path)


def write_exr(path, channels: dict, header: dict | None = None, *, overwrite: bool = True,
              half: bool = False) -> Path:
    """Write a scanline OpenEXR file atomically.

    Parameters
    ----------
    channels : dict of str -> ndarray (H, W)
        Channel name to pixels; stored as float32 (or float16 with *half*).
    header : dict
        Extra header attributes. Floats that need full precision should be passed as strings,
        because OpenEXR stores Python floats as 32-bit.
    """

    dtype = np.float16 if half else np.float32
    chans = {}
    shape = None
    for name, arr in channels.items():
        a = np.ascontiguousarray(np.asarray(arr, dtype=dtype))
        if a.ndim != 2:
            raise WaveopticsError(f"EXR channel {name!r} must be 2-D, got shape {a.shape}")
        if shape is not None and a.shape != shape:
            raise WaveopticsError(f"EXR channel {name!r} has shape {a.shape}, others {shape}")
        shape = a.shape
        chans[name] = a
    hdr = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    hdr.update(header or {})
    with atomic_path(path, overwrite=overwrite) as tmp:
        try:
            OpenEXR.File(hdr, chans).write(str(tmp))
        except RuntimeError as exc:   # the bindings report a full disk or an I/O error as RuntimeError
            raise WaveopticsError(f"cannot write {str(path)!r}: {exc}") from None
    return Path(path)


#: header attribute of an RGB EXR whose linear RGB holds colours outside its space's gamut (negative components)
OUT_OF_GAMUT_ATTR = "waveoptics_out_of_gamut"


def gamut_note(rgb, space: str = "sRGB") -> dict | None:
    """How many pixels of the linear RGB image *rgb* (..., 3) lie outside the gamut of *space* (a negative
    component), and the most negative component: ``{"pixels", "of", "min"}``, or None when every colour is inside.

    A non-negative spectrum (a BRDF, a radiance) can map to a negative RGB component: its chromaticity lies outside
    the triangle of the space's primaries (CIE 015:2018 §7; a narrow-band or steep spectrum, such as a diffraction
    tail that grows as λ⁻⁴). The value is kept, unclipped, and stated (:func:`write_rgb_exr`).
    """
    a = np.asarray(rgb, dtype=float).reshape(-1, 3)
    out = (a < 0).any(axis=1)
    if not out.any():
        return None
    return {"pixels": int(out.sum()), "of": int(a.shape[0]), "min": float(a.min()), "space": str(space)}


def write_rgb_exr(path, rgb, header: dict | None = None, *, space: str = "sRGB", overwrite: bool = True) -> dict | None:
    """Write a linear RGB image (H, W, 3) as an EXR with channels R, G, B (atomically), and return its
    :func:`gamut_note` (None when every colour lies inside the gamut).

    A non-finite value is refused (:class:`NonFiniteOutputError`). Colours outside the gamut of *space* keep their
    negative components (clipping would change the colour silently) and the file says so in the header attribute
    ``waveoptics_out_of_gamut``: how many pixels, the most negative component and that the spectral data behind
    them are non-negative.

    References
    ----------
    .. [1] CIE 015:2018, *Colorimetry*, §7 (tristimulus values of non-negative spectra; the spectrum locus lies
       outside every RGB triangle).
    """
    img = np.asarray(rgb, dtype=float)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise WaveopticsError(f"an RGB image must have shape (H, W, 3), got {img.shape}")
    if not np.all(np.isfinite(img)):
        raise NonFiniteOutputError(f"the image {Path(path).name} holds a NaN or infinite value")
    note = gamut_note(img.astype(np.float32), space)   # as stored: a component that rounds to -0 is not negative
    hdr = dict(header or {})
    if note is not None:
        hdr[OUT_OF_GAMUT_ATTR] = (f"{note['pixels']} of {note['of']} pixels lie outside the linear {space} gamut "
                                  f"(components down to {note['min']:.6g}); kept unclipped: their spectra are "
                                  "non-negative, their chromaticity lies outside the space's primaries")
    write_exr(path, {"R": img[..., 0], "G": img[..., 1], "B": img[..., 2]}, hdr, overwrite=overwrite)
    return note


def read_exr(path) -> tuple[dict, dict]:
    """Read an OpenEXR file: returns (channels as float arrays, header dict)."""

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"file {str(p)!r} does not exist")
    try:
        f = OpenEXR.File(str(p))
        chans = {name: np.asarray(c.pixels) for name, c in f.channels().items()}
        header = dict(f.header())
    except Exception as exc:  # noqa: BLE001 - the bindings raise plain RuntimeError/Exception
        raise WaveopticsError(f"{str(p)!r} is not a readable OpenEXR file ({exc})") from None
    return chans, header
