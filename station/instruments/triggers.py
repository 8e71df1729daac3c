"""The triggers a gauge set takes its reading sets by (standard library only: a procedure file
names one, and procedures load without the serial stack).

* ``poll``: each capture sends the requests; only answers read after the request count.
* ``push``: the device sends (DATA button, foot switch, data logger); a set completes when every
  channel has a reading since the last set.
* ``stable``: stream (polling continuously when the device is polled) and take the set once every
  channel has stayed within ``k`` × resolution for ``T`` ms.
* ``arrival``: read continuously (a background thread polls a polled device); the robot's own
  motion paces the cycles: a set is taken when the indicators have left their working band and
  come back to rest (:mod:`station.instruments.arrival`). Sets go to ``on_set`` as push sets do;
  a return that does not settle goes to ``on_arrival`` with a sentence, and is not a set.

How each is taken: :mod:`station.instruments.capture`.
"""

from __future__ import annotations

from typing import Literal

Trigger = Literal["poll", "push", "stable", "arrival"]
TRIGGERS: tuple[str, ...] = ("poll", "push", "stable", "arrival")
