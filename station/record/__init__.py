"""The calibration record: filed reports, each robot's history, before/after comparison and
baselines.

It sits above :mod:`station.session` and :mod:`station.analysis` and below the front ends: it
reads session files, never writes them, and imports no UI. Every analysis it shows comes through
one adapter, :func:`station.record.source.analyse_session`.
"""
