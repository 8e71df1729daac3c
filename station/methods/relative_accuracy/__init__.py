"""Relative accuracy (report §2.8.2): two fixtures, the teach pendant's X, Y, Z typed per
placement, the inverse move; the error at each placement and across placements."""

from station.methods.relative_accuracy.method import METHOD, RelativeAccuracy

__all__ = ["METHOD", "RelativeAccuracy"]
