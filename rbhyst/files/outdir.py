"""Where rbhyst writes: it replaces or removes only files it wrote itself.

A results folder may hold anything else (the deck, notes, other results). A command
writes its files into a hidden staging folder inside the target (``.rbhyst-staging-*``),
and only once all of them are written are they moved in, one ``os.replace`` each, with
SIGINT and SIGTERM held off. The folder's manifest ``.rbhyst.json`` lists the files
rbhyst wrote there: the next command into the same folder replaces those, removes those
it does not write again (a stale plot must not mislead), and refuses, before anything
is moved, to write over a file that is not listed. Nothing else is touched.

Single files (``make-record``) carry their mark in their first line instead.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import tempfile
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from rbhyst._version import __version__
from rbhyst.errors import DiskFull, InputError, byte_size, is_disk_full

MANIFEST = ".rbhyst.json"
STAGING_PREFIX = ".rbhyst-staging-"
_FORMAT_KEY, _FORMAT = "rbhyst_manifest", 1

#: what this process has written (folders and files), newest last: after an interrupt the
#: command line can say whether anything was
written: list[Path] = []

#: signals the command line's handler has seen, oldest first. Its handler raises, but an
#: exception raised where Python cannot pass it on (inside a ctypes callback, as when numba
#: loads a kernel) is lost: before committing, a recorded signal is raised again.
received: list[int] = []


@dataclass
class Manifest:
    """Paths relative to the folder, '/'-separated: the files rbhyst wrote, the subfolders it made."""

    files: set[str] = field(default_factory=set)
    folders: set[str] = field(default_factory=set)


@contextmanager
def staged_directory(target: Path, add: bool = False):
    """Yield a staging folder inside ``target``; on success its files move into ``target``.

    ``target`` (and its parents) is created if missing. Files an earlier rbhyst command
    wrote there are replaced, or removed when not written again (with ``add``, kept: the
    files join those of the command before, as a report joins its run's); a file that is in the way
    and is not rbhyst's is an InputError naming the folder and the file, and nothing is
    moved. On any exception (KeyboardInterrupt included) the staging folder is removed,
    and so are the folders this call created: ``target`` is left exactly as it was.
    """
    target = Path(target)
    created = _make_folders(target)
    try:
        owned = read_manifest(target)
        free = shutil.disk_usage(target).free
        tmp = Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=target))
    except OSError as exc:
        _remove_empty(created)
        raise InputError(f"{target}: cannot write into the folder ({exc.strerror or exc.__class__.__name__})") \
            from None
    except BaseException:
        _remove_empty(created)
        raise
    committed = False
    try:
        yield tmp
        if received:
            signal.raise_signal(received[-1])  # one that was lost on the way: stop before the commit
        files = _files_under(tmp)
        _check_in_the_way(target, files, owned)
        with signals_held():
            _commit(target, tmp, files, owned, add)
            committed = True
            written.append(target)
    except BaseException as exc:
        if not committed:  # (a signal held during the commit is raised after it: nothing to undo)
            staged = _bytes_under(tmp) if is_disk_full(exc) else 0
            with signals_held():
                shutil.rmtree(tmp, ignore_errors=True)
                _remove_empty(created)
            if is_disk_full(exc):  # (what was staged is a floor too: others may have freed space)
                raise DiskFull(target, max(staged, free)) from None
        raise


def check_free(target: Path, files: list[str]) -> None:
    """Before long work: the InputError staged_directory would raise at the end if any of
    ``files`` (relative, '/'-separated) is in ``target`` and is not rbhyst's."""
    target = Path(target)
    if target.is_dir():
        _check_in_the_way(target, files, read_manifest(target))


def replace_own_file(path: Path, text: str, mark: str) -> None:
    """Write ``text`` (whose first line starts with ``mark``) to ``path`` atomically.

    An existing ``path`` is replaced only if its own first line starts with ``mark``
    (rbhyst wrote it); any other file there is an InputError, and nothing is written.
    The text goes to a temporary file beside ``path`` first, then ``os.replace``.
    """
    path = Path(path)
    if not text.startswith(mark):
        raise ValueError("the text must begin with its mark")
    if path.is_dir():
        raise InputError(f"{path}: is a folder; give a file name")
    if (path.exists() or path.is_symlink()) and not _starts_with(path, mark):
        raise InputError(f"{path}: exists and rbhyst did not write it (its first line is not "
                         f"'{mark} ...'); rbhyst will not overwrite it: move it away or choose another name")
    created = _make_folders(path.parent)
    tmp = None
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".rbhyst-tmp", dir=path.parent)
        tmp = Path(name)
        if os.chmod in os.supports_fd:
            os.chmod(fd, 0o666 & ~_umask())  # mkstemp's 0600 would make the record private
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        with signals_held():
            os.replace(tmp, path)
            tmp = None
            written.append(path)
    except BaseException as exc:
        with signals_held():
            if tmp is not None:
                tmp.unlink(missing_ok=True)
            _remove_empty(created)
        if is_disk_full(exc):
            raise DiskFull(path.parent, None, f"{path.name} ({byte_size(len(text.encode()))})",
                           f"{path.name} was not changed") from None
        raise


@contextmanager
def signals_held():
    """SIGINT and SIGTERM wait until the block is done, then act as they would have.

    The block is not left half-done by Ctrl-C or a SIGTERM. The signal mask keeps them off
    this thread; the temporary handler catches one delivered to another thread. Only the
    main thread can do either; elsewhere the block simply runs.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = (signal.SIGINT, signal.SIGTERM)
    pending: list[int] = []
    previous: dict[int, object] = {}
    mask = None
    try:
        for s in held:
            previous[s] = signal.signal(s, lambda signum, frame: pending.append(signum))
        if hasattr(signal, "pthread_sigmask"):
            mask = signal.pthread_sigmask(signal.SIG_BLOCK, held)
        yield
    finally:
        if mask is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)  # a signal held meanwhile is recorded here
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        for s in dict.fromkeys(pending):
            signal.raise_signal(s)  # now handled as usual (KeyboardInterrupt, the CLI's handler, ...)


def read_manifest(folder: Path) -> Manifest:
    """The folder's manifest; none (no file) is an empty one, an unreadable one an InputError.

    Entries that would lead outside the folder, or to the manifest or a staging folder, are
    ignored: whatever they name is never rbhyst's to replace or remove.
    """
    path = Path(folder) / MANIFEST
    if not (path.exists() or path.is_symlink()):
        return Manifest()
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        data = None
    lists = [data.get(k) for k in ("files", "folders")] if isinstance(data, dict) else []
    if not (lists and data.get(_FORMAT_KEY) == _FORMAT
            and all(isinstance(v, list) and all(isinstance(x, str) for x in v) for v in lists)):
        raise InputError(f"{path}: not a manifest this rbhyst can read, so it cannot tell its own files from "
                         "others here; move the folder's contents away or choose another output folder")
    files, folders = lists
    return Manifest({x for x in files if _inside(x)}, {x for x in folders if _inside(x)})


#: the command whose results a folder holds, by the files only it writes there (first match)
RESULTS_OF = (("qualify", {"qualification.json"}), ("sweep", {"sweep.json"}),
              ("run", {"summary.json", "time_history.csv"}), ("calibrate", {"fitted.toml"}),
              ("calibrate-plot", {"summary.json"}), ("study", {"study.json"}),
              ("transmissibility", {"transmissibility.json"}), ("make-motion", {"motions.json", "trs.csv"}),
              ("spectrum", {"spectra.csv"}))


def results_of(folder: Path) -> str | None:
    """The rbhyst command whose results ``folder``'s manifest lists (None: none, or no manifest
    this rbhyst reads: the command then refuses the folder on its own)."""
    try:
        owned = read_manifest(folder).files
    except InputError:
        return None
    return next((command for command, files in RESULTS_OF if files <= owned), None)


def _inside(rel: str) -> bool:
    p = PurePosixPath(rel)
    return (bool(p.parts) and not p.is_absolute() and ".." not in p.parts and "\\" not in rel
            and p.parts[0] != MANIFEST and not p.parts[0].startswith(STAGING_PREFIX) and str(p) == rel)


def _files_under(tmp: Path) -> list[str]:
    out = []
    for root, _, names in os.walk(tmp):
        rel = Path(root).relative_to(tmp)
        out.extend((rel / n).as_posix() for n in names)
    if MANIFEST in out:
        raise ValueError(f"a command may not write {MANIFEST} itself")
    return sorted(out)


def _bytes_under(folder: Path) -> int:
    total = 0
    for root, _, names in os.walk(folder):
        for n in names:
            try:
                total += os.lstat(os.path.join(root, n)).st_size
            except OSError:
                pass
    return total


def _parents(rel: str) -> list[str]:
    """'a/b/c.csv' -> ['a', 'a/b']."""
    parts = PurePosixPath(rel).parts[:-1]
    return ["/".join(parts[:i]) for i in range(1, len(parts) + 1)]


def _occupied(path: Path) -> bool:
    return path.exists() or path.is_symlink()


def _check_in_the_way(target: Path, files: list[str], owned: Manifest) -> None:
    """InputError, one line per file, when a file to write would replace one rbhyst did not write."""
    problems = []
    for rel in files:
        for sub in _parents(rel):
            p = target / sub
            if _occupied(p) and (p.is_symlink() or not p.is_dir()):
                problems.append(f"{target}: rbhyst would write {rel}, but {sub} is in the way and rbhyst did "
                                "not make it; move it away or choose another output folder")
                break
        else:
            p = target / rel
            if _occupied(p) and (rel not in owned.files or (p.is_dir() and not p.is_symlink())):
                problems.append(f"{target}: {rel} exists and rbhyst did not write it (not listed in {MANIFEST}); "
                                "rbhyst will not overwrite it: move it away or choose another output folder")
    if problems:
        raise InputError(sorted(set(problems)))


def _commit(target: Path, tmp: Path, files: list[str], owned: Manifest, add: bool = False) -> None:
    new_folders = sorted({d for rel in files for d in _parents(rel) if not (target / d).is_dir()})
    folders = (owned.folders & {d for rel in files for d in _parents(rel)}) | set(new_folders)
    if add:  # the earlier files stay, and stay listed
        folders |= owned.folders
        files_after = set(files) | owned.files
    else:
        files_after = set(files)
    # first list both the old files and the new: a crash part-way leaves every file of ours named
    _write_manifest(target, tmp, Manifest(owned.files | set(files), owned.folders | folders))
    for d in new_folders:
        (target / d).mkdir(exist_ok=True)
    for rel in files:
        os.replace(tmp / rel, target / rel)
    for rel in sorted(owned.files - files_after):
        p = target / rel
        if p.is_symlink() or p.is_file():
            p.unlink()
    for d in sorted(owned.folders - folders, key=lambda d: -d.count("/")):
        try:
            (target / d).rmdir()  # only when empty: what someone else put there stays
        except OSError:
            pass
    try:
        _write_manifest(target, tmp, Manifest(files_after, folders))
    except OSError as exc:
        if not is_disk_full(exc):
            raise
        # the results are in; the manifest written first still names every file of ours
        # (names of removed ones too, which is harmless): leave it rather than fail a done job
    shutil.rmtree(tmp)


def _write_manifest(target: Path, tmp: Path, manifest: Manifest) -> None:
    data = {
        _FORMAT_KEY: _FORMAT,
        "about": "The files rbhyst wrote in this folder. The next rbhyst command writing here replaces or "
                 "removes these, and no others.",
        "rbhyst_version": __version__,
        "files": sorted(manifest.files),
        "folders": sorted(manifest.folders),
    }
    staged = tmp / MANIFEST
    staged.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    os.replace(staged, target / MANIFEST)


def _make_folders(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; return those created, outermost first."""
    missing = []
    p = Path(folder)
    while not _occupied(p) and p != p.parent:
        missing.append(p)
        p = p.parent
    created: list[Path] = []
    try:
        for p in reversed(missing):
            p.mkdir()
            created.append(p)
    except FileExistsError:
        pass  # made meanwhile by someone else: checked below
    except OSError as exc:
        _remove_empty(created)
        raise InputError(f"{p}: cannot create the folder ({exc.strerror or exc.__class__.__name__})") from None
    if not Path(folder).is_dir():
        _remove_empty(created)
        raise InputError(f"{folder}: exists and is not a folder; choose another output folder")
    return created


def _remove_empty(created: list[Path]) -> None:
    for p in reversed(created):
        try:
            p.rmdir()
        except OSError:
            break


def _starts_with(path: Path, mark: str) -> bool:
    try:
        with open(path, "rb") as fh:
            return fh.readline(len(mark.encode()) + 1).startswith(mark.encode())
    except OSError:
        return False


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
