"""The gauge check (a Type-1 study) before a verdict: one indicator reads a reference of known
size 25 to 50 times; Cg, Cgk, the bias and its t-test, filed in the gauge register."""

from station.methods.gauge_check.method import METHOD, GaugeCheckMethod

__all__ = ["METHOD", "GaugeCheckMethod"]
