"""A site's own step kinds and calibration methods: the objects installed distributions offer
under an entry-point group (``station.methods``, ``station.step_kinds``).

A site adds a method by installing a package whose metadata names it, e.g. in its
``pyproject.toml``::

    [project.entry-points."station.methods"]
    pose_drift = "site_methods.pose_drift:METHOD"

The station's own methods and step kinds are listed in explicit tuples
(:data:`station.methods.catalog.BUILT_IN`, :data:`station.run.steps.BUILT_IN`); these are read
beside them. The groups are scanned once per ``sys.path`` (a scan reads every installed
distribution's metadata, tens of milliseconds), and an entry point that fails to load is kept as
a sentence, never raised at a station that does not use it.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from functools import lru_cache
from importlib import metadata
from typing import Any

METHODS = "station.methods"
"""The entry-point group of a site's calibration methods (:class:`station.methods.Method`)."""
STEP_KINDS = "station.step_kinds"
"""The entry-point group of a site's step kinds (:class:`station.run.steps.StepHandler`)."""


@dataclass(frozen=True)
class SiteExtensions:
    """What one entry-point group offers: the objects loaded, and one sentence per entry point
    that failed to load (naming it and why)."""

    loaded: tuple[Any, ...] = ()
    failed: tuple[str, ...] = ()


def site_extensions(group: str) -> SiteExtensions:
    """The objects the installed distributions offer under entry-point ``group``."""
    return _scan(group, tuple(sys.path))


@lru_cache(maxsize=16)
def _scan(group: str, path: tuple[str, ...]) -> SiteExtensions:
    # ``path`` is the cache's key: a folder added to sys.path may hold another distribution.
    loaded: list[Any] = []
    failed: list[str] = []
    for entry in metadata.entry_points(group=group):
        try:
            loaded.append(entry.load())
        except Exception as error:  # a site's broken package must not stop the station
            failed.append(f"{entry.name} = {entry.value} did not load ({error})")
    return SiteExtensions(tuple(loaded), tuple(failed))
