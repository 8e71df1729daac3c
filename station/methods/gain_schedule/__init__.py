"""The gain schedule (report Part IV, §4.3): the gains tuned at a few positions fitted against
the position, for the controller to schedule."""

from station.methods.gain_schedule.method import METHOD, GainScheduleMethod

__all__ = ["METHOD", "GainScheduleMethod"]
