"""Output folders of ``python -m experiments run`` and ``sweep``: refuse what is not the toolkit's,
check that the folder can be written before computing, replace a previous output in one step.

The toolkit marks every folder it writes with ``jaxsim-output.json`` (:data:`MARKER`)::

    {"format": 1, "written_by": "python -m experiments", "command": "run" | "sweep",
     "study": NAME, "files": [the files it wrote, relative to the folder]}

Rules (:func:`check_output_folder`, called before anything is computed):

* a folder that does not exist, or an empty one, is fine;
* a folder whose marker says ``COMMAND NAME`` (the same command and study) and that holds nothing
  but the files its marker lists is this study's previous output: ``run`` replaces it, ``sweep``
  continues into it.  For ``sweep`` the checkpoint's ``manifest.json`` and ``chunks/`` count as the
  toolkit's, marker or not (a killed sweep has not written its marker yet); whether the checkpoint
  holds *this* sweep is the checkpoint's own check (:class:`jaxsim.montecarlo.store.ChunkStore`:
  another sweep is refused, and so are existing chunks without ``--resume``);
* a folder written before markers existed (no marker; its ``results.json`` names this study and
  every other file is a top-level CSV or PNG) counts as this study's previous output too, so that
  re-running a README command over an older output works;
* anything else — another study's or command's output, any file the toolkit did not write, a path
  that is not a folder — is refused with ``ValueError`` naming the folder and a few of the files;
* writability is probed by creating and removing a file: in the folder (or, if it does not exist
  yet, in its nearest existing parent) and, for ``run``, in its parent (where the new folder is
  assembled and swapped in).  A failure is a ``ValueError`` too.

``run`` writes into a fresh hidden sibling folder (:func:`staged_output`) and swaps it in at the end
— one atomic ``renameat2(RENAME_EXCHANGE)`` on Linux, else two renames — so an interrupted or failed
run leaves the previous output as it was and no half-written folder.  ``sweep`` writes its chunks
into the folder as it goes (that is what ``--resume`` reads), then its report files, each atomically,
between two updates of the marker (:func:`write_marker`) so that a crash never leaves an unlisted file.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import itertools
import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any, Iterator

MARKER = "jaxsim-output.json"
COMMANDS = ("run", "sweep")
_SHOWN = 5  # offending files named in a refusal
_PROBE = ".jaxsim-probe-"
# a crash's leftovers: temporaries of atomic_write_bytes, writability probes
_TEMPORARY = re.compile(r"\.[^/]+\.tmp-\d+|" + re.escape(_PROBE) + r"[^/]+")


def _listing(folder: Path) -> list[str]:
    """Every file under ``folder`` (relative, ``/``-separated; empty sub-folders as ``name/``), sorted."""

    def unreadable(exc: OSError) -> None:  # os.walk would skip it: a folder we cannot list is not "empty"
        raise exc

    found = []
    for root, dirs, files in os.walk(folder, onerror=unreadable):
        rel = Path(root).relative_to(folder)
        found += [(rel / f).as_posix() for f in files]
        found += [
            (rel / d).as_posix() + "/"
            for d in dirs
            if os.path.islink(os.path.join(root, d)) or not os.listdir(os.path.join(root, d))
        ]
    return sorted(f for f in found if f != MARKER)


def _read_marker(folder: Path) -> dict[str, Any] | None:
    path = folder / MARKER
    if not path.exists():
        return None
    try:
        marker = json.loads(path.read_text())
        files = marker.get("files") if isinstance(marker, dict) else None
        if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
            raise ValueError("not a marker of this toolkit")
    except (OSError, ValueError) as exc:
        raise ValueError(f"out: {path} is unreadable ({exc}); refusing to write into {folder}") from None
    return marker


def _toolkit_file(name: str, command: str) -> bool:
    """Files that are the toolkit's whatever the marker says: its temporaries, a sweep's checkpoint."""
    if _TEMPORARY.fullmatch(name):
        return True
    if command == "sweep":
        from jaxsim.montecarlo.store import CHUNKS, MANIFEST  # not at import: see experiments.report

        return name == MANIFEST or name.startswith(CHUNKS + "/")
    return False


def _legacy_files(folder: Path, study: str, command: str) -> set[str]:
    """A pre-marker output of this study: its ``results.json`` (naming the study) and top-level
    CSV/PNG files; empty if ``folder`` is not one."""
    try:
        written = json.loads((folder / "results.json").read_text()).get("study")
    except (OSError, ValueError, AttributeError):
        return set()
    if written != (study if command == "run" else f"{study} (sweep)"):
        return set()
    return {f for f in _listing(folder) if f == "results.json" or ("/" not in f and f.endswith((".csv", ".png")))}


def _check_owner(folder: Path, study: str, command: str) -> None:
    marker = _read_marker(folder)
    if marker is not None and (marker.get("command"), marker.get("study")) != (command, study):
        raise ValueError(
            f"out: {folder} holds the output of `{marker.get('command')} {marker.get('study')}`, not of "
            f"`{command} {study}`; nothing was computed — choose another folder or delete that one"
        )
    listed = set(marker["files"]) if marker is not None else _legacy_files(folder, study, command)
    foreign = [f for f in _listing(folder) if f not in listed and not _toolkit_file(f, command)]
    if foreign:
        shown = ", ".join(foreign[:_SHOWN]) + (f", … ({len(foreign)} in all)" if len(foreign) > _SHOWN else "")
        raise ValueError(
            f"out: {folder} holds files that are not a previous output of `{command} {study}`: {shown}; "
            "refusing to overwrite or remove them, nothing was computed — choose a new or empty folder "
            f"(a folder written by this toolkit carries {MARKER})"
        )


def _probe(folder: Path) -> None:
    """Create and remove a file in ``folder``; ``ValueError`` if the OS refuses."""
    try:
        fd, name = tempfile.mkstemp(prefix=_PROBE, dir=folder)
        os.close(fd)
        os.unlink(name)
    except OSError as exc:
        raise ValueError(f"out: cannot write into {folder} ({exc.strerror or exc}); nothing was computed") from None


def _existing_ancestor(path: Path) -> Path:
    p = path.absolute()
    while not p.exists():
        p = p.parent
    if not p.is_dir():
        raise ValueError(f"out: cannot create {path}: {p} is not a folder; nothing was computed")
    return p


def check_output_folder(path: str | Path, study: str, command: str) -> None:
    """Raise ``ValueError`` unless ``path`` may receive ``command``'s output of ``study`` (module rules).

    Args:
        path: the output folder (need not exist).
        study: the study's name.
        command: ``"run"`` (the folder will be replaced) or ``"sweep"`` (written into, resumable).
    """
    if command not in COMMANDS:
        raise ValueError(f"command: expected one of {COMMANDS}, got {command!r}")
    path = Path(path)
    if path.exists():
        if not path.is_dir():
            raise ValueError(f"out: {path} exists and is not a folder; nothing was computed")
        _check_owner(path, study, command)
        _probe(path)
        if command == "run":
            _probe(path.absolute().parent)
    else:
        _probe(_existing_ancestor(path))


def write_marker(folder: str | Path, study: str, command: str, files: list[str], *, final: bool = True) -> None:
    """Mark ``folder`` as ``command``'s output of ``study`` holding ``files`` (atomically).

    ``final=False`` (before writing ``files`` into a folder that may hold a previous output): the
    marker lists the previous marker's files and ``files``, so that whatever a crash leaves is
    listed.  ``final=True`` (after): it lists ``files`` alone; files the previous marker listed and
    ``files`` does not (a table an earlier run of the same sweep wrote and this one did not) are
    removed, and so are the toolkit's leftover temporaries.
    """
    from jaxsim.montecarlo.store import atomic_write_bytes  # not at import: see experiments.report

    folder = Path(folder)
    previous = [
        n
        for n in ((_read_marker(folder) or {}).get("files", []))
        if isinstance(n, str) and ".." not in Path(n).parts and not Path(n).is_absolute()
    ]
    if final:
        for name in previous:
            if name not in files:
                (folder / name).unlink(missing_ok=True)
        for name in _listing(folder):
            if "/" not in name and _TEMPORARY.fullmatch(name):
                (folder / name).unlink(missing_ok=True)
    listed = sorted(set(files) if final else set(files) | set(previous))
    marker = {"format": 1, "written_by": "python -m experiments", "command": command, "study": study, "files": listed}
    atomic_write_bytes(folder / MARKER, (json.dumps(marker, indent=1) + "\n").encode())


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one atomic step (Linux ``renameat2``); ``False`` where the OS cannot."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError, TypeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _swap_in(new: Path, path: Path) -> None:
    """Make ``new`` (a complete folder) appear at ``path``, replacing what was there."""
    if not path.exists():
        os.rename(new, path)
        return
    if _exchange(new, path):
        shutil.rmtree(new)  # now the previous output
        return
    old = new.with_name(new.name + ".old")
    os.rename(path, old)
    try:
        os.rename(new, path)
    except OSError:
        os.rename(old, path)
        raise
    shutil.rmtree(old)


def _new_sibling(parent: Path, stem: str) -> Path:
    """A new empty folder ``parent/stem-K`` (first free ``K``), with the usual permissions."""
    for k in itertools.count():
        try:
            (parent / f"{stem}-{k}").mkdir()
            return parent / f"{stem}-{k}"
        except FileExistsError:
            continue
    raise AssertionError("unreachable")  # pragma: no cover


@contextlib.contextmanager
def staged_output(path: str | Path, study: str) -> Iterator[Path]:
    """``with staged_output(DIR, NAME) as tmp:`` — for ``run``: check ``DIR`` (:func:`check_output_folder`),
    then yield a fresh empty folder beside it to write into.  On a clean exit the folder gets its
    marker and replaces ``DIR`` in one step; on an exception it is removed and ``DIR`` is untouched.
    """
    path = Path(os.path.abspath(path))  # "." or "a/.." have no name to put a sibling beside
    if path.is_symlink():
        path = path.resolve()  # replace the folder the link points to, not the link
    check_output_folder(path, study, "run")
    parent = path.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        staging = _new_sibling(parent, f".{path.name}.partial-{os.getpid()}")
    except OSError as exc:
        raise ValueError(f"out: cannot write beside {path} ({exc.strerror or exc}); nothing was computed") from None
    try:
        yield staging
        write_marker(staging, study, "run", _listing(staging))
        _swap_in(staging, path)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
