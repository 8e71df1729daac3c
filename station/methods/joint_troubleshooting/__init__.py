"""Per-joint troubleshooting (report §1.2, §2.8): each joint moved alone, away and back; the
joints ranked by their share of the spread and the suspect named."""

from station.methods.joint_troubleshooting.method import METHOD, JointTroubleshooting

__all__ = ["METHOD", "JointTroubleshooting"]
