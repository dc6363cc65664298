"""Writing results: whole output folders appear at once, single files by rename, CSV text.

Every command writes its output folder the same way (:func:`staged_folder`): the files go into
a fresh hidden folder beside the target (``.NAME.new-PID-XXXX``), and only once all of them are
written is that folder renamed into place in one step. An old result at the target is replaced
by an atomic exchange (Linux ``renameat2(RENAME_EXCHANGE)``; elsewhere two renames) and then
removed, so at any moment the target holds the old result or the new one, never a mix, and a
failed or killed run leaves the old one untouched. Files and folders are created with modes
0666/0777 less the user's umask, like any other program's output. A folder left behind by a
killed run (``.NAME.new-PID-*`` or ``.NAME.old-PID-*`` whose process is gone) is removed by the
next write to the same target; SIGTERM and SIGHUP remove what is staged before the process ends.
A single file (:func:`staged_file`) is staged in a private folder of the temporary folder, so a run
killed outright leaves nothing beside it.

An output folder is mtbmj's when it says so: every folder written here holds a record,
``.mtbmj-output.json``, of the command that wrote it and every file it wrote. A folder is replaced
only when it is empty or when each entry in it is named in that record (or is the folder's lock
file); a single file of anything else, whatever its name, means refusal. Every writer takes the
folder's lock (:func:`claim`, a POSIX lock on ``OUT/.lock`` that names its holder), so two mtbmj
runs never write into one folder at once.
"""
from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import shutil
import threading
import uuid
from pathlib import Path
from typing import Iterable, Iterator, Mapping

import numpy as np

from mtbmj.errors import MtbmjError, check_interrupt
from mtbmj.output.filesystem import (STAGE_PREFIX, TERMINATING, alive, clear_stale_stages,  # noqa: F401
                                     exchange, existing_ancestor, fsync_dir, glob_escape, link_tree,
                                     missing_ancestors, place_copy, register_stage, remove_empty, unregister_stage)

# The record of what mtbmj wrote into a folder, and the folder's lock file: an existing folder is
# replaced only when it is empty or every entry in it is named in its record (never by file names).
RECORD = ".mtbmj-output.json"
RECORD_FORMAT = "mtbmj output folder"
LOCK = ".lock"
BOOKKEEPING = (LOCK, RECORD)  # what every output folder holds besides the result itself

CSV_CHUNK_ROWS = 20000  # rows formatted at a time when a CSV is streamed to its file


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
        block = np.column_stack([a[start: start + rows] for a in arrays])
        # a subnormal is round-off where 0 is meant (a filter's tail run forward and back over a record's
        # leading zeros decays to 1e-317), and -0 is 0: both written 0
        block[np.abs(block) < np.finfo(float).tiny] = 0.0
        np.savetxt(buffer, block, delimiter=",", fmt="%.9g")
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


# A single output file (``render --out FILE``) is mtbmj's when a record beside it says so:
# ``.NAME.mtbmj-file.json`` holds the command, the size and the SHA-256 of what was written. A file
# that exists without that record, or whose bytes have changed since, is the user's and is never
# replaced.
FILE_RECORD_SUFFIX = ".mtbmj-file.json"
FILE_RECORD_FORMAT = "mtbmj output file"


def file_record_path(path: str | Path) -> Path:
    path = Path(path)
    return path.parent / f".{path.name}{FILE_RECORD_SUFFIX}"


def _sha256(path: Path) -> str:
    import hashlib

    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _file_is_ours(path: Path) -> bool:
    """Whether the regular file ``path`` is, byte for byte, what an mtbmj command wrote there."""
    record_path = file_record_path(path)
    try:
        if not record_path.is_file() or record_path.is_symlink() or record_path.stat().st_size > 65536:
            return False
        record = json.loads(record_path.read_text(encoding="utf-8"))
        if not isinstance(record, dict) or record.get("format") != FILE_RECORD_FORMAT:
            return False
        if record.get("name") != path.name:
            return False
        stat = path.stat()
        if stat.st_size != record.get("size_bytes"):
            return False
        return _sha256(path) == record.get("sha256")
    except (OSError, ValueError, UnicodeDecodeError):
        return False


def check_file_target(path: str | Path, what: str = "--out", error: type[MtbmjError] = MtbmjError) -> Path:
    """Refuse (``error``, one line), before any work, a single output file that cannot be written or
    that mtbmj did not write: a directory or link in its place, a special file, or a regular file
    with no record of ours beside it (or changed since). Also removes what killed runs left beside it."""
    path = Path(path)
    if path.is_symlink():
        raise error(f"{what} {path}: is a symbolic link; not replacing it: choose another name")
    if path.is_dir():
        raise error(f"{what} {path}: is a directory, not a file")
    if path.exists():
        if not path.is_file():
            raise error(f"{what} {path}: exists and is not a regular file; not replacing it")
        if not _file_is_ours(path):
            raise error(f"{what} {path}: exists and was not written by mtbmj (or was changed since); "
                             f"not replacing it: choose another name or remove it")
    parent = existing_ancestor(path.parent)
    if not parent.is_dir():
        raise error(f"{what} {path}: {parent} is not a directory")
    longest = os.pathconf(parent, "PC_NAME_MAX")  # refused here, before its folders are made and the work done
    for name in Path(os.path.abspath(path)).relative_to(parent).parts:
        if len(os.fsencode(name)) > longest:
            raise error(f"{what} {path}: a name of {len(os.fsencode(name))} bytes, longer than the {longest} the "
                        f"file system in {parent} allows")
    if not os.access(parent, os.W_OK | os.X_OK):
        read_only = bool(os.statvfs(parent).f_flag & os.ST_RDONLY)  # os.access says EROFS as it says EACCES
        raise error(f"{what} {path}: cannot write in {parent} "
                    f"({'a read-only file system' if read_only else 'permission denied'})")
    if path.parent.is_dir():
        _clear_stale(path)
    return path


@contextlib.contextmanager
def staged_file(path: str | Path, command: str = "python", what: str = "--out",
                error: type[MtbmjError] = MtbmjError) -> Iterator[Path]:
    """Write one output file: yields a fresh path named like ``path`` in a private staging folder
    (``TMPDIR/mtbmj-stage-PID-XXXX/``) for the caller to fill; on a clean exit the file is put in
    place (a new name by a link that never replaces anything; an older file of ours by an atomic
    rename, after checking again that it is still ours) and its record written beside it. On any
    exception, on Ctrl-C and on SIGTERM or SIGHUP, the staged file is removed; a run killed outright
    (SIGKILL) leaves nothing beside the target (its staging folder is removed by the next staging,
    its process being gone)."""
    import tempfile

    path = check_file_target(path, what, error)
    created = missing_ancestors(path.parent)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise error(f"{what} {path}: cannot write ({exc.strerror})") from None
    clear_stale_stages()
    try:
        folder = Path(tempfile.mkdtemp(prefix=f"{STAGE_PREFIX}{os.getpid()}-"))
    except OSError as exc:
        if not path.exists():
            remove_empty(created)
        raise error(f"{what} {path}: cannot stage the file in the temporary folder ({exc.strerror})") from None
    register_stage(folder, True)
    stage = folder / path.name
    try:
        try:
            yield stage
            check_interrupt()
            if not stage.is_file():
                raise error(f"{what} {path}: nothing was written")
            record = {"format": FILE_RECORD_FORMAT, "command": command, "name": path.name,
                      "size_bytes": stage.stat().st_size, "sha256": _sha256(stage)}
            if path.exists() or path.is_symlink():
                check_file_target(path, what, error)  # still ours now that the work is done?
                place_copy(stage, path, replace=True)
            else:
                try:
                    place_copy(stage, path, replace=False)
                except FileExistsError:
                    raise error(f"{what} {path}: a file appeared there while mtbmj worked; "
                                f"not replacing it") from None
            write_file_atomically(file_record_path(path), json_bytes(record))
            fsync_dir(path.parent)
        except OSError as exc:
            raise error(f"{what} {path}: cannot write ({exc.strerror or exc})") from None
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)  # before the folders it made are removed
        if not path.exists():
            remove_empty(created)
        raise
    finally:
        shutil.rmtree(folder, ignore_errors=True)  # (after a link the staged name is still there)
        unregister_stage(folder)


def check_target(out_dir: str | Path, inputs: Iterable[str | Path] = ()) -> Path:
    """Refuse, before any work, an output folder that cannot be written: a file in its place, a
    parent where no folder can be made, the current directory, a folder holding anything mtbmj
    did not write (see :func:`foreign_entry`), or one holding any of ``inputs`` (the files the
    command reads). Creates nothing that stays."""
    out = Path(out_dir)
    if out.is_symlink():  # (the swap replaces a folder, never a link: refused now, not after the work)
        raise MtbmjError(f"{out}: is a symbolic link; give the folder itself as --out")
    if out.exists() and not out.is_dir():
        raise MtbmjError(f"{out}: exists and is not a directory; choose another --out")
    here = Path.cwd().resolve()
    if out.resolve() == here or out.resolve() in here.parents:
        raise MtbmjError(f"{out}: is the current directory or holds it; choose another --out")
    _check_inputs(out, inputs)
    if out.is_dir():
        _refuse_foreign(out)
    parent = existing_ancestor(out.parent)
    if not parent.is_dir():
        raise MtbmjError(f"{parent}: is not a directory, so {out} cannot be made")
    probe = parent / f".{out.name}.probe-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        os.mkdir(probe)
        os.rmdir(probe)
    except OSError as exc:
        raise MtbmjError(f"{out}: cannot write output here ({exc.strerror})") from None
    return out


def _check_inputs(out: Path, inputs: Iterable[str | Path]) -> None:
    root = out.resolve()
    for item in inputs:
        path = Path(item).resolve()
        if path == root or root in path.parents:
            raise MtbmjError(f"{out}: holds {item}, which this command reads; replacing the folder would remove "
                             f"it: choose another --out")


def read_record(out: Path) -> dict | None:
    """The record of what mtbmj wrote into ``out`` (``None``: none, or not one of ours)."""
    try:
        record = json.loads((out / RECORD).read_text())
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if (not isinstance(record, dict) or record.get("format") != RECORD_FORMAT
            or not isinstance(record.get("files"), list) or not isinstance(record.get("folders", []), list)):
        return None
    return record


def foreign_entry(out: str | Path) -> str | None:
    """The first entry of the folder ``out`` (a path relative to it) that mtbmj did not write,
    or ``None`` when every entry is named in its record: the files the record lists, the folders
    that hold them, the folders it owns whole (a sweep's journal), the record itself and the lock
    file. Names do not count: a user's ``manifest.json`` is as foreign as their ``thesis.tex``."""
    out = Path(out)
    record = read_record(out) or {"files": [], "folders": []}
    files = {str(f) for f in record["files"]} | {RECORD, LOCK}
    folders = {str(f).rstrip("/") for f in record.get("folders", [])}
    parents = {str(p) for f in files for p in Path(f).parents}
    for root, dirs, names in os.walk(out):
        rel_root = Path(root).relative_to(out)
        for name in sorted(dirs):
            rel = str(rel_root / name)
            if Path(root, name).is_symlink():
                if rel not in files:
                    return rel
                dirs.remove(name)
            elif rel in folders or any(rel.startswith(f + "/") for f in folders):
                dirs.remove(name)
            elif rel not in parents:
                return rel
        for name in sorted(names):
            rel = str(rel_root / name)
            if rel == LOCK and not _is_our_lock(out / LOCK):
                return rel
            if rel_root == Path(".") and name.startswith(f".{RECORD}.new-"):
                continue  # a record being replaced (or left by a killed run)
            if rel not in files and not any(rel.startswith(f + "/") for f in folders):
                return rel
    return None


def _is_our_lock(path: Path) -> bool:
    try:
        with open(path, "rb") as handle:
            head = handle.read(64)
    except OSError:
        return False
    return head == b"" or head.startswith(b"mtbmj ")


def _refuse_foreign(out: Path) -> None:
    entry = foreign_entry(out)
    if entry is not None:
        older = (" (the folder looks like the result of an mtbmj older than its output records: if you no longer "
                 "need it, remove it yourself)" if read_record(out) is None and _older_result(out) else "")
        raise MtbmjError(f"{out}: holds {entry}, which mtbmj did not write (it is not in {RECORD}); writing here "
                         f"would replace it: choose another --out{older}")


def _older_result(out: Path) -> bool:
    """``out`` holds a manifest an mtbmj before output records wrote (its ``versions`` name mtbmj).
    Only a hint for the refusal: such a folder is still refused, never replaced."""
    for name in ("manifest.json", "sweep.json"):
        try:
            manifest = json.loads((out / name).read_text())
        except (OSError, ValueError, UnicodeDecodeError):
            continue
        if isinstance(manifest, dict) and isinstance(manifest.get("versions"), dict) and "mtbmj" in manifest["versions"]:
            return True
    return False


class Claim:
    """This process's hold on an output folder: its lock file open and locked (see :func:`claim`)."""

    def __init__(self, out: Path, command: str):
        self.out, self.command = out, command
        self.fd: int | None = None
        self.made = False  # the claim created the folder (removed again if nothing was written)
        self.written = False  # a result was swapped in
        self.folders: set[str] = set()


_CLAIMS: dict[str, Claim] = {}
_CLAIMS_LOCK = threading.RLock()


def _refuse_other_command(out: Path, command: str) -> None:
    """A folder another command wrote is not replaced by this one (``advise --out out/reconstruct``
    replaced the reconstruction a later ``bike --speed-profile`` reads): each command replaces its own
    result only (``fit``'s kinds share one, as they share its default folder). A program's folder
    (command ``python``), or a program writing, is not told apart."""
    record = read_record(out) if out.is_dir() else None
    other = str((record or {}).get("command") or "python")
    if "python" in (command, other) or other.split()[0] == command.split()[0]:
        return
    raise MtbmjError(f"{out}: holds the result of mtbmj {other}, which {command} would replace: choose another --out "
                     f"(or remove the folder first)")


@contextlib.contextmanager
def claim(out_dir: str | Path, command: str = "python", folders: Iterable[str] = (),
          inputs: Iterable[str | Path] = ()) -> Iterator[Claim]:
    """``with claim(out, "drop"):`` hold the folder ``out`` for one writer, before any work.

    Checks the target (:func:`check_target`), makes the folder if it is missing, and takes an
    exclusive POSIX lock (``lockf``) on ``OUT/.lock``, writing the holder (command and process) into
    it; a second writer, in this process or another, is refused at once with one line naming the
    holder. The lock belongs to the process: forked workers do not hold it, and it goes when the
    process does, even killed. Results staged while the claim is held carry the same lock file
    (a hard link), so the lock holds across the swap. ``folders`` are sub-folders the holder
    writes piece by piece before its result (a sweep's journal): they are recorded as mtbmj's at
    once, so an interrupted run can be resumed. A folder the claim made and left without a
    result is removed. Claims nest in one process (the command line's, then the writer's)."""
    out = Path(out_dir)
    key = os.path.abspath(out)
    with _CLAIMS_LOCK:
        held = _CLAIMS.get(key)
    if held is not None:
        if folders:
            held.folders |= set(folders)
            _write_record(out, held.command, _record_files(out), held.folders)
        yield held
        return
    import fcntl

    if (out / LOCK).is_file():
        _refuse_if_locked(out)
    check_target(out, inputs)
    _refuse_other_command(out, command)
    held = Claim(out, command)
    created = missing_ancestors(out)
    try:
        held.made = not out.exists()
        out.mkdir(parents=True, exist_ok=True)
        held.fd = os.open(out / LOCK, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o666)
    except OSError as exc:
        _release(held, created)
        raise MtbmjError(f"{out}: cannot write output here ({exc.strerror})") from None
    try:
        fcntl.lockf(held.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(held.fd)
        held.fd = None
        raise _busy(out) from None
    try:
        os.ftruncate(held.fd, 0)
        os.pwrite(held.fd, f"mtbmj {command} (process {os.getpid()})\n".encode(), 0)
        held.folders = set(folders)
        if held.folders:  # recorded now: a run stopped before its result can be resumed
            _write_record(out, command, _record_files(out), held.folders | set((read_record(out) or {}).get("folders", [])))
    except OSError as exc:
        _release(held, created)
        raise MtbmjError(f"{out}: cannot write output here ({exc.strerror})") from None
    except BaseException:
        _release(held, created)
        raise
    with _CLAIMS_LOCK:
        _CLAIMS[key] = held
    try:
        yield held
    finally:
        with _CLAIMS_LOCK:
            _CLAIMS.pop(key, None)
        _release(held, created)


def _refuse_if_locked(out: Path) -> None:
    """Refuse at once when another process holds ``OUT/.lock`` (before asking whose the files are)."""
    import fcntl

    try:
        fd = os.open(out / LOCK, os.O_RDWR | getattr(os, "O_CLOEXEC", 0))
    except OSError:
        return
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        raise _busy(out) from None
    finally:
        os.close(fd)  # also releases the probe's lock


def _busy(out: Path) -> MtbmjError:
    """The refusal of a folder another process holds, naming the holder its lock file names."""
    try:
        text = (out / LOCK).read_bytes()[:200].decode("utf-8", "replace").strip()
    except OSError:
        text = ""
    holder = " (" + text.replace("\n", " ").replace("\r", " ") + ")" if text.startswith("mtbmj ") else ""
    return MtbmjError(f"{out}: another mtbmj run{holder} is writing to this folder; wait for it or choose another --out")


def _release(held: Claim, created: list[Path]) -> None:
    out = held.out
    try:
        if held.made and not held.written and _only_bookkeeping(out, held.folders):
            shutil.rmtree(out, ignore_errors=True)
            remove_empty(created[1:])  # (made: the first missing folder was ``out`` itself)
    finally:
        if held.fd is not None:
            os.close(held.fd)  # releases the lock
            held.fd = None


def _only_bookkeeping(out: Path, folders: set[str]) -> bool:
    """``out`` holds nothing but the record, the lock and empty owned folders."""
    try:
        for entry in out.iterdir():
            if entry.name in (RECORD, LOCK):
                continue
            if entry.name in folders and entry.is_dir() and not any(entry.iterdir()):
                continue
            return False
    except OSError:
        return False
    return True


def _record_files(out: Path) -> list[str]:
    """What a record names in ``out`` as it is now (used only on folders already known to be ours)."""
    record = read_record(out)
    return [f for f in (record or {}).get("files", []) if (out / f).exists()] + [LOCK]


def _record_bytes(command: str, files: Iterable[str], folders: Iterable[str]) -> bytes:
    from mtbmj._package import __version__

    return json_bytes({"format": RECORD_FORMAT, "command": command, "mtbmj": __version__,
                       "files": sorted(set(files) - {RECORD}), "folders": sorted(set(folders))})


def _write_record(out: Path, command: str, files: Iterable[str], folders: Iterable[str]) -> None:
    """Replace ``OUT/.mtbmj-output.json`` (beside it, then renamed: a killed write leaves a
    ``.mtbmj-output.json.new-*`` that :func:`foreign_entry` passes over)."""
    write_file_atomically(out / RECORD, _record_bytes(command, files, folders))


def _stage_files(stage: Path) -> list[str]:
    names = []
    for root, _dirs, files in os.walk(stage):
        for name in files:
            names.append(str((Path(root) / name).relative_to(stage)))
    return names


@contextlib.contextmanager
def staged_folder(out_dir: str | Path, keep: Iterable[str] = ()) -> Iterator[Path]:
    """``with staged_folder(out) as stage:`` write the result into ``stage``; when the block ends
    without an error the folder ``out`` is replaced by it in one step (see the module doc).
    ``keep`` names entries of an existing ``out`` carried into the new folder (hard links, so
    a sweep's journal stays the same files); the lock file always is. The folder is claimed
    (:func:`claim`) for the time it takes, unless this process holds it already; just before the
    swap it is checked again, so a file someone put there meanwhile is never removed."""
    out = Path(out_dir)
    keep = tuple(dict.fromkeys(tuple(keep) + (LOCK,)))
    with claim(out) as held:
        _clear_stale(out)
        try:
            stage = out.parent / f".{out.name}.new-{os.getpid()}-{uuid.uuid4().hex[:8]}"
            os.mkdir(stage, 0o777)
        except OSError as exc:
            raise MtbmjError(f"{out}: cannot write results ({exc.strerror})") from None
        register_stage(stage, True)  # removed on SIGTERM or SIGHUP too
        try:
            for name in keep:
                if (out / name).exists():
                    link_tree(out / name, stage / name)
            yield stage
            kept_folders = {name for name in keep if (stage / name).is_dir()}
            write_file(stage / RECORD, _record_bytes(held.command, _stage_files(stage), kept_folders))
            fsync_dir(stage)
            check_interrupt()
            _refuse_foreign(out)
            _swap_into_place(stage, out)
            held.written = True
        except OSError as exc:
            shutil.rmtree(stage, ignore_errors=True)
            raise MtbmjError(f"{out}: cannot write results ({exc.strerror or exc})") from None
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
        finally:
            unregister_stage(stage)


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
    if exchange(stage, out):
        shutil.rmtree(stage, ignore_errors=True)  # the old result, now at the staging name
    else:  # no atomic exchange here: two renames, the old folder kept until the new one is in place
        old = out.parent / f".{out.name}.old-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        os.rename(out, old)
        os.rename(stage, out)
        shutil.rmtree(old, ignore_errors=True)
    fsync_dir(out.parent)


def _clear_stale(out: Path) -> None:
    """Remove staging and probe folders of ``out`` left by runs that were killed (their process
    is gone)."""
    for prefix in (f".{out.name}.new-", f".{out.name}.old-", f".{out.name}.probe-"):
        for path in out.parent.glob(f"{glob_escape(prefix)}*"):
            pid = path.name[len(prefix):].split("-", 1)[0]
            if pid.isdigit() and int(pid) != os.getpid() and not alive(int(pid)):
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    path.unlink(missing_ok=True)


