"""A virtual robot with its end effector in a fixture, speaking a gauge protocol on a pty or TCP.

Two halves, so later procedures add models without touching the server:

* a **model** (:class:`RobotModel`, :mod:`.models`) says what each gauge shows: the
  repeatability fixture (:class:`FixtureModel`), two fixtures and a teach pendant for relative
  accuracy (:class:`TwoFixtureModel`, :mod:`.two_fixture`), a parallel bar for linearity
  (:class:`BarModel`, :mod:`.bar`); the gauge bench and the 3-joint arm live beside this
  package (:mod:`station.instruments.gauge_bench`, :mod:`station.instruments.joint_model`);
* the **server** (:class:`Simulator`, :mod:`.server`) speaks a protocol on a line
  (:mod:`.line`: a pseudo-terminal or a TCP port), with seeded fault injection
  (:class:`Faults`).
"""

from station.instruments.simulator.bar import BarModel
from station.instruments.simulator.models import (
    AxisModel,
    FixtureModel,
    GaugeSpec,
    RampModel,
    RobotModel,
    demo_model,
    fixture_model,
    skew_normal_unit,
)
from station.instruments.simulator.server import Faults, SentFrame, Simulator
from station.instruments.simulator.two_fixture import Placement, TwoFixtureModel

__all__ = [
    "AxisModel",
    "BarModel",
    "Faults",
    "FixtureModel",
    "GaugeSpec",
    "Placement",
    "RampModel",
    "RobotModel",
    "SentFrame",
    "Simulator",
    "TwoFixtureModel",
    "demo_model",
    "fixture_model",
    "skew_normal_unit",
]
