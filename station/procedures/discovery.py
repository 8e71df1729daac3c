"""Finding procedures: the built-in folder, a site's folders (``STATION_PROCEDURES`` and
``--procedures``), one procedure per id (a later folder's wins and the catalog says so)."""

from __future__ import annotations

import importlib.resources
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import station
from station.errors import StationError
from station.procedures.loading import load_procedure
from station.procedures.model import Procedure, ProcedureCatalog

PROCEDURES_ENV = "STATION_PROCEDURES"


def builtin_procedures_dir() -> Path:
    """The folder of the procedures that ship with station.

    In an installed wheel they are the package ``station.builtin_procedures`` (pyproject maps the
    top-level ``procedures/`` folder there); in a source or editable checkout that package does
    not import, so the checkout's ``procedures/`` folder is used.
    """
    try:
        # The folder has no __init__.py: on Python 3.11 files() of such a namespace package is
        # a MultiplexedPath, so find the folder through the files it holds.
        for entry in importlib.resources.files("station.builtin_procedures").iterdir():
            if entry.name.endswith(".toml") and isinstance(entry, Path):
                return entry.parent
    except (ModuleNotFoundError, TypeError, ValueError, OSError):
        pass

    return Path(station.__file__).resolve().parent.parent / "procedures"


def procedure_dirs_from_env(environ: Mapping[str, str] | None = None) -> tuple[Path, ...]:
    """The folders named in ``STATION_PROCEDURES`` (``os.pathsep``-separated), in order."""
    value = (os.environ if environ is None else environ).get(PROCEDURES_ENV, "")
    return tuple(Path(part) for part in value.split(os.pathsep) if part.strip())


def discover_procedures(
    extra_dirs: Sequence[str | os.PathLike[str]] = (),
    *,
    use_env: bool = True,
) -> ProcedureCatalog:
    """The built-in procedures plus a site's folders, one per id.

    Folders are read in order: built-in, then ``STATION_PROCEDURES`` (when ``use_env``), then
    ``extra_dirs`` (from ``--procedures``); a later folder's procedure with the same id wins and
    the catalog's notes say so. A named folder that does not exist is a StationError; a file
    that fails to load is listed in ``notes``/``errors`` and skipped, so one bad file does not
    hide the others.
    """
    builtin = builtin_procedures_dir()
    folders: list[tuple[Path, bool]] = [(builtin, True)]
    user_dirs = [*(procedure_dirs_from_env() if use_env else ()), *map(Path, extra_dirs)]
    for folder in user_dirs:
        if not folder.is_dir():
            raise StationError(
                f"procedures folder {folder} does not exist (from the command line or "
                f"{PROCEDURES_ENV}); create it or fix the path"
            )
        if folder.resolve() != builtin.resolve():
            folders.append((folder, False))

    chosen: dict[str, tuple[Procedure, bool]] = {}
    overridden: dict[str, Path] = {}
    overrides_builtin: set[str] = set()
    notes: list[str] = []
    errors: list[str] = []
    for folder, is_builtin in folders:
        for path in sorted(folder.glob("*.toml")):
            try:
                procedure = load_procedure(path)
            except StationError as error:
                errors.append(error.message)
                continue
            previous = chosen.get(procedure.id)
            if previous is not None:
                old, old_builtin = previous
                if old.path.resolve() == path.resolve():
                    continue
                overridden[procedure.id] = old.path
                if old_builtin:
                    overrides_builtin.add(procedure.id)
                what = "built-in" if old_builtin else str(old.path)
                notes.append(f"{procedure.id}: {path} overrides {what} ({old.path})")
            chosen[procedure.id] = (procedure, is_builtin)
    procedures = tuple(p for p, _ in sorted(chosen.values(), key=lambda item: item[0].id))
    builtin_ids = frozenset(p.id for p, is_builtin in chosen.values() if is_builtin)
    notes.extend(f"skipped: {message}" for message in errors)
    return ProcedureCatalog(
        procedures=procedures,
        builtin_ids=builtin_ids,
        overridden=overridden,
        notes=tuple(notes),
        errors=tuple(errors),
        overrides_builtin=frozenset(overrides_builtin),
    )
