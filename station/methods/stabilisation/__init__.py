"""Position stabilisation time and overshoot, ISO 9283 §7.4–7.5 (issue 21, item 2)."""

from station.methods.stabilisation.method import METHOD, StabilisationMethod

__all__ = ["METHOD", "StabilisationMethod"]
