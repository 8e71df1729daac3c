"""What a gauge set's frames say: the unit and resolution the kept frames show, compared with
the session's (:mod:`station.instruments.units` holds the pure inference)."""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping

from station.instruments.units import FrameInference, FrameSample, frames_disagree, infer_channel


class SetFrameChecks:
    """:meth:`frame_samples`, :meth:`infer_frames` and :meth:`check_frames` (a part of
    :class:`~station.instruments.gauge.GaugeSet`, whose kept readings, readers and captures it
    uses)."""

    def frame_samples(self, channels: Iterable[str] | None = None) -> dict[str, list[FrameSample]]:
        """What the kept readings' frames show, per channel: the device value (before any
        software zero), the decimals written and the unit stated."""
        wanted = list(self.channels if channels is None else channels)
        with self._changed:
            kept = {c: list(self._history[c]) for c in wanted}
        samples: dict[str, list[FrameSample]] = {}
        for channel, readings in kept.items():
            protocol = self._reader_of[channel].protocol
            samples[channel] = [
                FrameSample(
                    r.device_value,
                    protocol.frame_decimals(r.raw.encode("ascii", "backslashreplace")),
                    r.frame_unit,
                )
                for r in readings
            ]
        return samples

    def infer_frames(self, channels: Iterable[str] | None = None) -> dict[str, FrameInference]:
        """The unit and resolution each channel's kept frames show (:func:`infer_channel`)."""
        return {
            channel: infer_channel(
                channel, samples, self._reader_of[channel].protocol.units_by_decimals
            )
            for channel, samples in self.frame_samples(channels).items()
        }

    def check_frames(
        self,
        unit: str,
        resolution: float | Mapping[str, float] | None = None,
        *,
        readings: int = 5,
        timeout: float = 2.0,
        channels: Iterable[str] | None = None,
    ) -> str:
        """'' when the frames agree with ``unit`` and ``resolution`` (default: this set's);
        else the sentence naming both (no full stop), e.g. "the gauges send steps of 0.001,
        which is mm on this protocol; the session is in inches at 0.0001".

        Reads up to ``readings`` more readings per channel first (:meth:`collect`, no settle
        window; a push device that is not pressed gives none within ``timeout``), then judges
        every kept frame. A channel that sent nothing says nothing.
        """
        wanted = list(self.channels if channels is None else channels)
        if self.trigger in ("poll", "stable") and all(
            self._reader_of[c].protocol.polled for c in wanted
        ):
            # One request per reading, each answered before the next: the gauges are asked
            # exactly ``readings`` times (a device, or a simulated robot, that counts its
            # readings sees a known number).
            deadline = time.monotonic() + timeout
            for _ in range(readings):
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                self._capture_poll(remaining)
        else:
            self.collect(wanted, readings, 0.0, timeout)
        samples = self.frame_samples(wanted)
        inferred = {
            c: infer_channel(c, samples[c], self._reader_of[c].protocol.units_by_decimals)
            for c in wanted
        }
        return frames_disagree(
            inferred, unit, self.resolution if resolution is None else resolution, samples
        )
