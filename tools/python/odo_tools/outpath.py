"""The output rule of every Python tool that writes files: the twin of hostlib/odo_out.h.

- Missing parent folders are created (and removed again if the run fails).
- A file output is written into a fresh temp beside the target (O_CREAT|O_EXCL|O_NOFOLLOW, mode
  0666 & ~umask), fsync'd and renamed into place. The target, if it exists, must be a regular
  file: a folder, symlink, FIFO, device or socket is refused with an error naming it.
- A folder output is built in a fresh temp folder beside the target. An absent or empty target
  receives it by rename. A target holding this tool's manifest (MANIFEST, the same format the C
  tools write) may have exactly the files of that manifest replaced or removed; everything else
  stays. Any other non-empty folder is refused unless force, and with force the tool's files
  replace same-named files and nothing else is removed.
- An output that is also an input (same device and inode as an input file or folder, or inside an
  input folder) is refused before anything is written.
- Temps are removed on any exception, at exit, and on SIGTERM/SIGHUP (turned into SystemExit so
  the context managers clean up); a failed run leaves the target as it was.

Use `out_file(path, inputs)` for one file and `OutDir(path, tool, force, inputs)` for a folder,
both as context managers. Refusals raise OutputError (str: 'path: why')."""

from __future__ import annotations

import atexit
import contextlib
import os
import secrets
import shutil
import signal
import stat
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

MANIFEST = ".odo-manifest"
MAGIC = "odo-out-manifest 1"

_TEMPS: set[Path] = set()  # temp files/folders of this process, removed at exit if still there


class OutputError(Exception):
    """An output the rule refuses or cannot write; str() is 'path: why'."""

    def __init__(self, path: str | Path, why: str) -> None:
        self.path = str(path)
        self.why = why
        super().__init__(f"{self.path}: {why}")

    def __reduce__(self):
        return type(self), (self.path, self.why)  # rebuilt from its arguments (errors.py)


def _cleanup() -> None:
    for p in sorted(_TEMPS, key=lambda q: len(q.parts), reverse=True):
        with contextlib.suppress(OSError):
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p)
            else:
                p.unlink()
    _TEMPS.clear()


def _on_signal(sig: int, _frame: object) -> None:
    raise SystemExit(128 + sig)  # unwinds through the context managers, which remove their temps


_installed = False


def _install() -> None:
    global _installed
    if _installed:
        return
    _installed = True
    atexit.register(_cleanup)
    for sig in (signal.SIGTERM, signal.SIGHUP):
        with contextlib.suppress(ValueError, OSError):  # not the main thread: leave it be
            if signal.getsignal(sig) == signal.SIG_DFL:
                signal.signal(sig, _on_signal)


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISREG, "a file"),
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISLNK, "a symbolic link"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


class Inputs:
    """Identities (device, inode) of a tool's input files and folders, taken before any output."""

    def __init__(self, paths: Iterable[str | Path | None] = ()) -> None:
        self.items: list[tuple[int, int, bool, str]] = []
        for p in paths:
            self.add(p)

    def add(self, p: str | Path | None) -> None:
        if p is None:
            return
        try:
            st = os.stat(p)
        except OSError:
            return  # the tool reports a missing input when it reads it
        self.items.append((st.st_dev, st.st_ino, stat.S_ISDIR(st.st_mode), str(p)))

    def _match(self, st: os.stat_result, dirs_only: bool) -> str | None:
        for dev, ino, is_dir, path in self.items:
            if dev == st.st_dev and ino == st.st_ino and (is_dir or not dirs_only):
                return path
        return None

    def check(self, path: str | Path) -> None:
        """Raise OutputError if writing `path` could touch an input."""
        p = Path(path)
        with contextlib.suppress(OSError):
            hit = self._match(os.stat(p), False)
            if hit is not None:
                raise OutputError(
                    p, f"the output is also an input ({hit}); refusing to overwrite it"
                )
        for anc in Path(os.path.abspath(p)).parents:
            with contextlib.suppress(OSError):
                hit = self._match(os.stat(anc), True)
                if hit is not None:
                    raise OutputError(
                        p, f"the output lies inside the input folder {hit}; refusing to write there"
                    )


def _as_inputs(inputs: Inputs | Iterable[str | Path | None] | None) -> Inputs:
    if isinstance(inputs, Inputs):
        return inputs
    return Inputs(inputs or ())


def _make_parents(folder: Path) -> list[Path]:
    """mkdir -p; returns the folders made, outermost first."""
    made: list[Path] = []
    missing = []
    for anc in [folder, *folder.parents]:
        if anc.exists():
            if not anc.is_dir():
                raise OutputError(anc, "is not a folder")
            break
        if anc.is_symlink():
            raise OutputError(anc, "is a dangling symbolic link")
        missing.append(anc)
    for d in reversed(missing):
        try:
            d.mkdir()
        except FileExistsError:
            continue
        except OSError as e:
            _undo_parents(made)
            raise OutputError(d, f"cannot create folder: {e.strerror}") from None
        made.append(d)
        _TEMPS.add(d)
    return made


def _undo_parents(made: list[Path]) -> None:
    for d in reversed(made):
        with contextlib.suppress(OSError):
            d.rmdir()
        _TEMPS.discard(d)


def _keep_parents(made: list[Path]) -> None:
    for d in made:
        _TEMPS.discard(d)


def _check_file_target(p: Path) -> None:
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        return
    except NotADirectoryError:
        return  # an ancestor is a file: _make_parents names it
    if not stat.S_ISREG(st.st_mode):
        raise OutputError(p, f"is {_kind(st.st_mode)}, not a regular file; refusing to replace it")


def _fresh_file(folder: Path, base: str) -> tuple[Path, int]:
    for _ in range(100):
        tmp = folder / f".{base}.tmp-{os.getpid()}-{secrets.token_hex(3)}"
        try:
            fd = os.open(
                tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666
            )
        except FileExistsError:
            continue  # never ours: a planted link or another process's temp
        except OSError as e:
            raise OutputError(folder, f"cannot create a temp file: {e.strerror}") from None
        _TEMPS.add(tmp)
        return tmp, fd
    raise OutputError(folder, "cannot create a temp file: every name taken")


def _fsync_dir(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextlib.contextmanager
def out_file(
    path: str | Path,
    inputs: Inputs | Iterable[str | Path | None] | None = None,
    mode: str = "w",
    **open_kw: Any,
) -> Iterator[IO[Any]]:
    """Write one file by the rule: yields a file object on a fresh temp beside `path`, renamed
    into place when the block ends without an exception (else removed, target untouched)."""
    _install()
    p = Path(path)
    if p.name in ("", ".", ".."):
        raise OutputError(p, "is not a file name")
    _check_file_target(p)
    _as_inputs(inputs).check(p)
    made = _make_parents(p.parent)
    try:
        tmp, fd = _fresh_file(p.parent, p.name)
    except BaseException:
        _undo_parents(made)
        raise
    try:
        with os.fdopen(fd, mode, **open_kw) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        _check_file_target(p)  # again: a FIFO or link planted during the run is not replaced
        os.replace(tmp, p)
        _TEMPS.discard(tmp)
        _fsync_dir(p.parent)
        _keep_parents(made)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        _TEMPS.discard(tmp)
        _undo_parents(made)
        raise


def write_bytes(path: str | Path, data: bytes, inputs: Any = None) -> None:
    with out_file(path, inputs, "wb") as f:
        f.write(data)


def write_text(path: str | Path, text: str, inputs: Any = None) -> None:
    with out_file(path, inputs, "w", encoding="utf-8") as f:
        f.write(text)


def _name_ok(name: str) -> bool:
    if not name or name.startswith("/") or len(name) >= 1024 or name == MANIFEST:
        return False
    if any(ord(c) < 0x20 or ord(c) == 0x7F for c in name):
        return False
    return all(part not in ("", ".", "..") for part in name.split("/"))


def read_manifest(folder: Path, tool: str) -> list[str] | None:
    """The files `tool` listed in folder's manifest, or None (absent, foreign or malformed)."""
    try:
        fd = os.open(folder / MANIFEST, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as fh:
        raw = fh.read(1 << 22)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        return None
    if not text.endswith("\n"):
        return None
    lines = text[:-1].split("\n")
    if len(lines) < 2 or lines[0] != MAGIC or lines[1] != f"tool {tool}":
        return None
    names = lines[2:]
    return names if all(_name_ok(n) for n in names) else None


def _manifest_text(tool: str, names: Iterable[str]) -> str:
    return "".join(f"{line}\n" for line in [MAGIC, f"tool {tool}", *names])


def _target(path: Path, tool: str, force: bool, inputs: Inputs) -> tuple[str, list[str]]:
    """How `tool` may write the folder `path` ("fresh", "update" with the old manifest's names,
    or "force"), or OutputError where the rule forbids it."""
    if path.name in ("", ".", ".."):
        raise OutputError(path, "is not a folder name")
    inputs.check(path)
    try:
        st = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return "fresh", []
    if not stat.S_ISDIR(st.st_mode):
        raise OutputError(path, f"is {_kind(st.st_mode)}, not a folder; refusing to replace it")
    if not any(os.scandir(path)):
        return "fresh", []
    if (old := read_manifest(path, tool)) is not None:
        return "update", old
    if force:
        return "force", []
    raise OutputError(
        path,
        f"is a non-empty folder {tool} did not write (no {MANIFEST} of its own in it); "
        "refusing to write there (--force writes into it, replacing same-named files and "
        "removing nothing)",
    )


def check_dir(
    path: str | Path,
    tool: str,
    force: bool = False,
    inputs: Inputs | Iterable[str | Path | None] | None = None,
) -> None:
    """OutputError now where OutDir(path, tool, force, inputs) would refuse later: a tool that
    works for a while before it writes checks first, so a user is not kept waiting for a
    refusal. Nothing is created (OutDir checks again: the folder may change meanwhile)."""
    _target(Path(path), tool, force, _as_inputs(inputs))


class OutDir:
    """Build an output folder by the rule. Write into `self.tmp` (a fresh folder beside the
    target: open files there or hand it to a writer); every file under it at the end is the
    tool's output, listed in the manifest. On a clean exit the files go into place; on an
    exception the temp folder (and parents made for it) is removed and the target is untouched."""

    def __init__(
        self,
        path: str | Path,
        tool: str,
        force: bool = False,
        inputs: Inputs | Iterable[str | Path | None] | None = None,
    ) -> None:
        _install()
        self.path = Path(path)
        self.tool = tool
        self.inputs = _as_inputs(inputs)
        self.mode, self.old = _target(self.path, tool, force, self.inputs)
        self._made = _make_parents(self.path.parent)
        for _ in range(100):
            tmp = self.path.parent / f".{self.path.name}.tmp-{os.getpid()}-{secrets.token_hex(3)}"
            try:
                tmp.mkdir(mode=0o700)
            except FileExistsError:
                continue
            except OSError as e:
                _undo_parents(self._made)
                raise OutputError(self.path, f"cannot create a temp folder: {e.strerror}") from None
            break
        else:
            _undo_parents(self._made)
            raise OutputError(self.path, "cannot create a temp folder: every name taken")
        self.tmp = tmp
        _TEMPS.add(tmp)

    def __enter__(self) -> OutDir:
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.abort()

    def abort(self) -> None:
        shutil.rmtree(self.tmp, ignore_errors=True)
        _TEMPS.discard(self.tmp)
        _undo_parents(self._made)

    def _files(self) -> list[str]:
        names = []
        for root, dirs, files in os.walk(self.tmp):
            dirs.sort()
            for f in sorted(files):
                rel = os.path.relpath(os.path.join(root, f), self.tmp).replace(os.sep, "/")
                full = Path(root) / f
                if full.is_symlink() or not full.is_file():
                    raise OutputError(self.path / rel, "the tool made something not a regular file")
                if rel == MANIFEST or not _name_ok(rel):
                    raise OutputError(self.path / rel, "is not a name an output folder may hold")
                names.append(rel)
        return sorted(names)

    def commit(self) -> None:
        try:
            names = self._files()
            for n in names:
                fd = os.open(self.tmp / n, os.O_RDONLY)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
            if self.mode == "fresh":
                (self.tmp / MANIFEST).write_text(_manifest_text(self.tool, names))
                um = os.umask(0o22)
                os.umask(um)
                os.chmod(self.tmp, 0o777 & ~um)
                if self.path.exists() and (not self.path.is_dir() or any(os.scandir(self.path))):
                    raise OutputError(self.path, "appeared during the run; not replacing it")
                os.rename(self.tmp, self.path)
                _TEMPS.discard(self.tmp)
                _fsync_dir(self.path.parent)
                _keep_parents(self._made)
                return
            # Into an existing folder: check every destination before touching any.
            for n in names:
                dst = self.path / n
                try:
                    st = os.lstat(dst)
                except FileNotFoundError:
                    continue
                if not stat.S_ISREG(st.st_mode):
                    raise OutputError(dst, f"is {_kind(st.st_mode)}; refusing to replace it")
                self.inputs.check(dst)
            both = names + [o for o in self.old if o not in names]
            write_text(self.path / MANIFEST, _manifest_text(self.tool, both))
            for n in names:
                dst = self.path / n
                dst.parent.mkdir(parents=True, exist_ok=True)
                os.replace(self.tmp / n, dst)
            if self.mode == "update":
                for o in self.old:
                    if o in names:
                        continue
                    dst = self.path / o
                    with contextlib.suppress(OSError, OutputError):
                        if stat.S_ISREG(os.lstat(dst).st_mode):
                            self.inputs.check(dst)
                            dst.unlink()
            write_text(self.path / MANIFEST, _manifest_text(self.tool, names))
            _fsync_dir(self.path)
            _keep_parents(self._made)
        except OSError as e:
            self.abort()
            raise OutputError(self.path, f"cannot write: {e.strerror or e}") from None
        except BaseException:
            self.abort()
            raise
        shutil.rmtree(self.tmp, ignore_errors=True)
        _TEMPS.discard(self.tmp)
