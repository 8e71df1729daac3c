"""The crossed Gage R&R study (AIAG MSA, 4th ed.): appraisers each measure the same parts in
trials, the parts in a fresh random order each trial; the repeatability, reproducibility and
part variation by ANOVA and by average and range, %GRR, ndc and AIAG's verdict."""

from station.methods.gage_rr.method import METHOD, GageRR

__all__ = ["METHOD", "GageRR"]
