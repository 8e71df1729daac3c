"""Repeatability (report §2.6): 25 to 30 cycles at one taught point, each channel's readings
judged by capability."""

from station.methods.repeatability.method import METHOD, Repeatability

__all__ = ["METHOD", "Repeatability"]
