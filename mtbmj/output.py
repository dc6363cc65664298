"""Writing results: whole output folders appear at once, single files by rename, CSV text.

Every command writes its output folder the same way (:func:`staged_folder`): the files go into
a fresh hidden folder beside the target (``.NAME.new-PID-XXXX``), and only once all of them are
written is that folder renamed into place in one step. An old result at the target is replaced
by an atomic exchange (Linux ``renameat2(RENAME_EXCHANGE)``; elsewhere two renames) and then
removed, so at any moment the target holds the old result or the new one, never a mix, and a
failed or killed run leaves the old one untouched. Files and folders are created with modes
0666/0777 less the user's umask, like any other program's output. A folder left behind by a
killed run (``.NAME.new-PID-*`` or ``.NAME.old-PID-*`` whose process is gone) is removed by the
next write to the same target.
"""
from __future__ import annotations

import contextlib
import ctypes
import errno
import io
import json
import os
import shutil
import uuid
from pathlib import Path
from typing import Iterable, Iterator, Mapping

import numpy as np

from mtbmj.errors import MtbmjError

# An existing folder is replaced only when it is empty or holds an mtbmj result, recognised by
# the summary file each command writes (or a sweep's journal): never a folder of other files.
RESULT_FILES = ("manifest.json", "sweep.json", "fit.json", "telemetry.json", "study_summary.json",
                "validation_summary.json", "sensitivity.json", "journal", ".lock")

CSV_CHUNK_ROWS = 20000  # rows formatted at a time when a CSV is streamed to its file
_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def csv_chunks(columns: Mapping[str, np.ndarray], header: str = "", rows: int = CSV_CHUNK_ROWS):
    """The CSV text of ``columns`` (name -> values) as bytes chunks of ``rows`` rows each, so a
    long run is written without its whole text in memory; joined, they are ``csv_bytes``."""
    names = list(columns)
    arrays = [np.asarray(columns[n], dtype=float) for n in names]
    lines = [f"# {line}\n" for line in header.splitlines()] if header else []
    yield ("".join(lines) + ",".join(names) + "\n").encode()
    n = len(arrays[0]) if arrays else 0
    for start in range(0, n, rows):
        buffer = io.StringIO()
        np.savetxt(buffer, np.column_stack([a[start: start + rows] for a in arrays]), delimiter=",", fmt="%.9g")
        text = buffer.getvalue()
        buffer.close()  # savetxt leaves a reference cycle to the buffer: free its text now, not at the next GC
        yield text.encode()


def csv_bytes(columns: Mapping[str, np.ndarray], header: str = "") -> bytes:
    return b"".join(csv_chunks(columns, header))


def spreadsheet_text(value):
    """Text a user may have chosen (a file or configuration name, a reason), made safe for a CSV
    cell that a spreadsheet opens: a leading ``= + - @`` (or tab, carriage return) that it would
    run as a formula gets a leading apostrophe. Numbers and other values pass unchanged."""
    if not isinstance(value, str) or value[:1] not in ("=", "+", "-", "@", "\t", "\r"):
        return value
    try:
        float(value)  # a negative number stays a number
        return value
    except ValueError:
        return "'" + value


def json_bytes(data) -> bytes:
    return (json.dumps(data, indent=2, sort_keys=False) + "\n").encode()


def write_file(path: str | Path, content) -> Path:
    """Write one new file (mode 0666 less the umask) and flush it to disk. ``content`` is bytes
    or an iterable of bytes chunks (written as they come, e.g. ``csv_chunks``)."""
    path = Path(path)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    with os.fdopen(fd, "wb") as handle:
        if isinstance(content, (bytes, bytearray, memoryview)):
            handle.write(content)
        else:
            for chunk in content:
                handle.write(chunk)
        handle.flush()
        os.fsync(handle.fileno())
    return path


def write_file_atomically(path: str | Path, content: bytes) -> Path:
    """Replace or create the single file ``path``: written beside it, then renamed into place."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.is_dir():
            raise MtbmjError(f"{path}: is a directory, not a file")
        tmp = path.parent / f".{path.name}.new-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        try:
            write_file(tmp, content)
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
    except OSError as exc:
        raise MtbmjError(f"{path}: cannot write ({exc.strerror})") from None
    return path


def check_target(out_dir: str | Path) -> Path:
    """Refuse, before any work, an output folder that cannot be written: a file in its place, a
    parent where no folder can be made, the current directory, or a folder of other files (see
    :data:`RESULT_FILES`). Creates nothing that stays."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise MtbmjError(f"{out}: exists and is not a directory; choose another --out")
    here = Path.cwd().resolve()
    if out.resolve() == here or out.resolve() in here.parents:
        raise MtbmjError(f"{out}: is the current directory or holds it; choose another --out")
    if out.is_dir() and not any((out / name).exists() for name in RESULT_FILES) and any(out.iterdir()):
        raise MtbmjError(f"{out}: holds files that are not an mtbmj result, which writing here would replace; "
                         f"choose another --out")
    parent = _existing_ancestor(out.parent)
    if not parent.is_dir():
        raise MtbmjError(f"{parent}: is not a directory, so {out} cannot be made")
    probe = parent / f".{out.name}.probe-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        os.mkdir(probe)
        os.rmdir(probe)
    except OSError as exc:
        raise MtbmjError(f"{out}: cannot write output here ({exc.strerror})") from None
    return out


@contextlib.contextmanager
def staged_folder(out_dir: str | Path, keep: Iterable[str] = ()) -> Iterator[Path]:
    """``with staged_folder(out) as stage:`` write the result into ``stage``; when the block ends
    without an error the folder ``out`` is replaced by it in one step (see the module doc).
    ``keep`` names entries of an existing ``out`` carried into the new folder (hard links, so
    a sweep's journal and lock file stay the same files)."""
    out = check_target(out_dir)
    created = _missing_ancestors(out.parent)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        _clear_stale(out)
        stage = out.parent / f".{out.name}.new-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        os.mkdir(stage, 0o777)
    except OSError as exc:
        _remove_empty(created)
        raise MtbmjError(f"{out}: cannot write results ({exc.strerror})") from None
    try:
        if out.is_dir():
            for name in keep:
                if (out / name).exists():
                    _link_tree(out / name, stage / name)
        yield stage
        fsync_dir(stage)
        _swap_into_place(stage, out)
    except OSError as exc:
        shutil.rmtree(stage, ignore_errors=True)
        _remove_empty(created)
        raise MtbmjError(f"{out}: cannot write results ({exc.strerror or exc})") from None
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        _remove_empty(created)
        raise


def write_atomically(out_dir: str | Path, files: Mapping[str, bytes], keep: Iterable[str] = ()) -> list[Path]:
    """Make ``out_dir`` hold exactly ``files`` (name -> content; names may hold ``/``) plus the
    ``keep`` entries of the old folder, all at once (see :func:`staged_folder`)."""
    out = Path(out_dir)
    with staged_folder(out, keep) as stage:
        for name, content in files.items():
            target = stage / name
            target.parent.mkdir(parents=True, exist_ok=True)
            write_file(target, content)
    return [out / name for name in files]


def _swap_into_place(stage: Path, out: Path) -> None:
    try:
        os.rename(stage, out)  # no folder (or an empty one) at the target: one rename
        fsync_dir(out.parent)
        return
    except OSError as exc:
        if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR, errno.EISDIR):
            raise
    if out.is_symlink() or not out.is_dir():
        raise MtbmjError(f"{out}: exists and is not a directory; choose another --out")
    if _exchange(stage, out):
        shutil.rmtree(stage, ignore_errors=True)  # the old result, now at the staging name
    else:  # no atomic exchange here: two renames, the old folder kept until the new one is in place
        old = out.parent / f".{out.name}.old-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        os.rename(out, old)
        os.rename(stage, out)
        shutil.rmtree(old, ignore_errors=True)
    fsync_dir(out.parent)


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically (Linux renameat2); False where that is not available."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint)
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _link_tree(src: Path, dst: Path) -> None:
    if src.is_dir() and not src.is_symlink():
        os.mkdir(dst, 0o777)
        for child in src.iterdir():
            _link_tree(child, dst / child.name)
        return
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)


def _clear_stale(out: Path) -> None:
    """Remove staging and probe folders of ``out`` left by runs that were killed (their process
    is gone)."""
    for prefix in (f".{out.name}.new-", f".{out.name}.old-", f".{out.name}.probe-"):
        for path in out.parent.glob(f"{_glob_escape(prefix)}*"):
            pid = path.name[len(prefix):].split("-", 1)[0]
            if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    path.unlink(missing_ok=True)


def _glob_escape(text: str) -> str:
    return "".join(f"[{c}]" if c in "*?[]" else c for c in text)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def _existing_ancestor(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _missing_ancestors(path: Path) -> list[Path]:
    missing = []
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        missing.append(path)
        path = path.parent
    return missing  # deepest first


def _remove_empty(paths: list[Path]) -> None:
    for path in paths:
        try:
            path.rmdir()
        except OSError:
            return


def fsync_dir(path: Path) -> None:
    """Flush a folder's entries (a rename into it) to disk; best effort."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
