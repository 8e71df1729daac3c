"""How many examples a property test tries.

A property test states the count it wants for a thorough search, ``max_examples=examples(N)``;
the default run tries at most :data:`QUICK` of them, so the whole suite stays fast, and
``pytest --hypothesis-profile=thorough`` (the long property run) tries all ``N``. Hypothesis
draws its seed from ``random``, which pytest-randomly seeds per test: ``--randomly-seed=S``
with the seed a run printed repeats its examples.
"""

from __future__ import annotations

from hypothesis import settings

QUICK = 100
"""The most examples a property test tries in the default run (Hypothesis's own default)."""
THOROUGH = "thorough"
"""The profile of the long property run (registered by tests/conftest.py)."""


def examples(thorough: int) -> int:
    """``thorough`` under the thorough profile, else at most :data:`QUICK`."""
    if settings.get_current_profile_name() == THOROUGH:
        return thorough
    return min(thorough, QUICK)
