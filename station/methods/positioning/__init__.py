"""Axis positioning, ISO 230-2: the bidirectional accuracy and repeatability of one axis, each
target approached 5 times up and 5 times down in the standard test cycle; the reversal B, the
repeatability R, the systematic error E, the mean bidirectional error M and the accuracy A."""

from station.methods.positioning.method import METHOD, Positioning

__all__ = ["METHOD", "Positioning"]
