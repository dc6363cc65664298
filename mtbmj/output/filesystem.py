"""What writing results does to the file system: the paths this process has staged (removed on
SIGTERM or SIGHUP before the process ends, and the private staging folders of runs that are gone
removed by the next staging), a staged file put in place by a link, a rename or a copy, the atomic
exchange of two folders, hard-linked trees, and a folder's entries flushed to disk. The rules of
when and what is written are ``mtbmj.output``'s."""
from __future__ import annotations

import ctypes
import errno
import os
import shutil
import threading
import uuid
from pathlib import Path

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100

# Where single files are staged while they are written: a private folder in the system's temporary
# folder (``mtbmj-stage-PID-XXXX``), never beside the target, so that a run killed outright (SIGKILL)
# leaves nothing beside the user's file; the next staging removes such folders of runs that are gone.
STAGE_PREFIX = "mtbmj-stage-"
TERMINATING = ("SIGTERM", "SIGHUP")  # signals whose default ends the process: staging is removed first
_STAGED: dict[Path, bool] = {}  # what this process has staged now -> whether it is a folder
_STAGED_LOCK = threading.Lock()
_PREVIOUS_HANDLERS: dict = {}
_STAGE_OWNER = {"pid": None}  # the process that staged (a worker forked meanwhile inherits the handler, not the stages)


def remove_staged(path: Path) -> None:
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
    except OSError:
        pass


def _on_terminate(signum, frame) -> None:
    """SIGTERM or SIGHUP while something is staged: remove it, then end as the signal would have."""
    import signal

    if os.getpid() == _STAGE_OWNER["pid"]:
        for path in list(_STAGED):
            remove_staged(path)
    _STAGED.clear()
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)


def register_stage(path: Path, folder: bool) -> None:
    """Remember ``path`` as staged; the first one installs the terminating signals' handler (in the
    main thread, where the signal's action is still the default: never over a caller's own)."""
    import signal

    with _STAGED_LOCK:
        first = not _STAGED
        _STAGED[path] = folder
        _STAGE_OWNER["pid"] = os.getpid()
        if first and threading.current_thread() is threading.main_thread():
            for name in TERMINATING:
                number = getattr(signal, name, None)
                if number is not None and signal.getsignal(number) == signal.SIG_DFL:
                    _PREVIOUS_HANDLERS[number] = signal.signal(number, _on_terminate)


def unregister_stage(path: Path) -> None:
    import signal

    with _STAGED_LOCK:
        _STAGED.pop(path, None)
        if not _STAGED and threading.current_thread() is threading.main_thread():
            for number, previous in list(_PREVIOUS_HANDLERS.items()):
                if signal.getsignal(number) is _on_terminate:
                    signal.signal(number, previous)
                del _PREVIOUS_HANDLERS[number]


def clear_stale_stages() -> None:
    """Remove private staging folders (``STAGE_PREFIX``PID-*) of this user's runs that are gone."""
    import tempfile

    root = Path(tempfile.gettempdir())
    try:
        candidates = list(root.glob(f"{glob_escape(STAGE_PREFIX)}*"))
    except OSError:
        return
    for path in candidates:
        pid = path.name[len(STAGE_PREFIX):].split("-", 1)[0]
        try:
            mine = path.is_dir() and not path.is_symlink() and path.stat().st_uid == os.getuid()
        except OSError:
            continue
        if mine and pid.isdigit() and int(pid) != os.getpid() and not alive(int(pid)):
            shutil.rmtree(path, ignore_errors=True)


def place_copy(stage: Path, path: Path, replace: bool) -> None:
    """Put ``stage`` (in the private staging folder) at ``path``: by a link or rename where both are on
    one file system, else by a copy beside ``path`` (``.NAME.new-PID-XXXX.EXT``, there only for the
    moment of the copy) that is then linked or renamed into place."""
    try:
        if replace:
            os.replace(stage, path)
        else:
            os.link(stage, path)  # never replaces a file that appeared meanwhile
        return
    except OSError as exc:
        if exc.errno not in (errno.EXDEV, errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK):
            raise
    beside = path.parent / f".{path.name}.new-{os.getpid()}-{uuid.uuid4().hex[:8]}{path.suffix}"
    register_stage(beside, False)
    try:
        shutil.copyfile(stage, beside)
        with open(beside, "rb") as handle:
            os.fsync(handle.fileno())
        if replace:
            os.replace(beside, path)
        else:
            try:
                os.link(beside, path)
            except OSError as exc:
                if isinstance(exc, FileExistsError) or path.exists():
                    raise
                os.replace(beside, path)  # (a file system without hard links)
    finally:
        beside.unlink(missing_ok=True)
        unregister_stage(beside)


def exchange(a: Path, b: Path) -> bool:
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


def link_tree(src: Path, dst: Path) -> None:
    if src.is_dir() and not src.is_symlink():
        os.mkdir(dst, 0o777)
        for child in src.iterdir():
            link_tree(child, dst / child.name)
        return
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)


def glob_escape(text: str) -> str:
    return "".join(f"[{c}]" if c in "*?[]" else c for c in text)


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def existing_ancestor(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def missing_ancestors(path: Path) -> list[Path]:
    missing = []
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        missing.append(path)
        path = path.parent
    return missing  # deepest first


def remove_empty(paths: list[Path]) -> None:
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


__all__ = ["STAGE_PREFIX", "TERMINATING", "alive", "clear_stale_stages", "exchange", "existing_ancestor", "fsync_dir", "glob_escape", "link_tree", "missing_ancestors", "place_copy", "register_stage", "remove_empty", "remove_staged", "unregister_stage"]
