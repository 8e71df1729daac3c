"""The gauge linearity and bias study (AIAG MSA, 4th ed.): five or more reference masters
spanning the range, each read 10 to 12 times, re-seated; the bias per master with its t-test,
its regression on the size, the linearity and the average bias, filed in the gauge register."""

from station.methods.gauge_linearity.method import METHOD, GaugeLinearity

__all__ = ["METHOD", "GaugeLinearity"]
