"""The ISO 9283 pose characteristics test: a fixture at each pose of the test cube through the
standard's cycle; AP and RP per pose, vAP, AD and RD, and the run's conditions."""

from station.methods.pose_characteristics.method import METHOD, PoseCharacteristicsMethod

__all__ = ["METHOD", "PoseCharacteristicsMethod"]
