"""Linearity (report §2.9): two perpendicular indicators and a linear scale along a parallel
bar, 25 to 30 strokes streamed; the straightness of each stroke judged against its tolerance."""

from station.methods.linearity.method import METHOD, Linearity

__all__ = ["METHOD", "Linearity"]
