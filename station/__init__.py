"""station: a terminal acquisition station for statistical robot calibration."""

__version__ = "0.1.0"
