"""Zeroing a gauge set: several readings per channel over a settle window, then the device's
zero command or a software offset.

:meth:`SetZeroing.collect` reads every channel a number of times (polling a polled port, or
listening to one that pushes); :meth:`SetZeroing.zero` refuses while a gauge moves or reads in
another unit (the judgement is :mod:`station.instruments.zeroing`'s, pure) and then sends each
device's command or sets each software offset. A port that is down is waited for until the
timeout, as a capture waits for it.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping

from station.errors import StationError
from station.instruments.capture import at_stop_sentence
from station.instruments.reader import GaugeReader, GaugeReading, TriggerTicket
from station.instruments.units import unit_mismatch
from station.instruments.zeroing import (
    DEFAULT_ZERO_STILL,
    ChannelZero,
    NotAtFixture,
    zero_from_readings,
)


class SetZeroing:
    """:meth:`zero` and :meth:`collect` (a part of :class:`~station.instruments.gauge.GaugeSet`,
    whose attributes it uses: the readers by channel, the resolutions, the collectors its
    reading intake fills under the ``_changed`` condition, the arrival streaming thread)."""

    def zero(
        self,
        channels: Iterable[str] | None = None,
        timeout: float = 2.0,
        *,
        unit: str | None = None,
        readings: int = 1,
        settle: float = 0.0,
        still: float = DEFAULT_ZERO_STILL,
    ) -> list[ChannelZero]:
        """Zero ``channels`` (all by default): the device's command, else a software offset.

        With the ``arrival`` trigger (the robot runs its loop) the zero first waits, up to
        ``timeout``, for the robot to be at rest at the fixture: every channel resting more than
        its band from its free-travel stop on the cube's side, the stop stated by the procedure
        or learned from a round trip seen (:class:`~station.instruments.travel.TravelWatch`);
        and its readings must all come from that one rest. With any trigger, readings at a known
        stop are refused. Either refusal is a
        :class:`~station.instruments.zeroing.NotAtFixture` (nothing zeroed).

        With ``readings`` > 1 every channel is read ``readings`` times over ``settle`` seconds
        (:meth:`collect`); the zero is refused (StationError naming the channel, nothing
        zeroed) while a channel's readings spread over more than ``still`` resolutions or too
        few arrive. Then a software channel's offset is the mean of its readings and a device
        channel gets its zero command. With ``readings`` = 1 (the old way) a software zero takes
        one fresh reading set and a device zero reads nothing. With ``unit`` it refuses a
        channel reading in another unit. A port that is down is waited for until ``timeout``
        (counted after the settle window). Returns one
        :class:`~station.instruments.zeroing.ChannelZero` per channel, in ``channels``' order:
        its :meth:`~station.instruments.zeroing.ChannelZero.record` is the zero event's entry.
        """
        wanted = list(self.channels if channels is None else channels)
        unknown = [c for c in wanted if c not in self._reader_of]
        if unknown:
            raise StationError(
                f"Cannot zero {', '.join(unknown)}: this station's channels are "
                f"{', '.join(self.channels)}."
            )
        if readings < 1:
            raise StationError(f"A zero needs at least 1 reading per channel, not {readings}.")
        commands = {c: self._zero_command(c) for c in wanted}
        rests, since = None, None
        if self.trigger == "arrival":
            rests, since = self._wait_at_fixture(wanted, timeout)
        if readings == 1:
            return self._zero_once(wanted, commands, timeout, unit)
        # Under arrival the readings that showed the rest count: a robot on its loop rests
        # only so long at the fixture.
        taken = self.collect(wanted, readings, settle, timeout, since=since)
        self._refuse_away(taken, wanted, rests)
        down = [
            c
            for c in wanted
            if len(taken[c]) < readings and self._reader_of[c].state != "connected"
        ]
        if down:
            reader = self._reader_of[down[0]]
            raise StationError(
                f"Could not zero {', '.join(down)}: {reader.down_message()}. Check the cable "
                "and try again."
            )
        if unit is not None:
            latest = {c: values[-1] for c, values in taken.items() if values}
            mismatch = unit_mismatch(latest, wanted, unit)
            if mismatch:
                raise StationError(f"Could not zero: {mismatch}.")
        spans = [v[-1].t_mono - v[0].t_mono for v in taken.values() if v]
        zeros = zero_from_readings(
            {c: [r.device_value for r in taken[c]] for c in wanted},
            self.resolution,
            methods={c: "device" if commands[c] else "software" for c in wanted},
            min_readings=readings,
            still=still,
            window=max(spans, default=0.0),
            unit=unit or "",
        )
        self._apply_zeros(zeros, commands, timeout)
        return list(zeros)

    def _wait_at_fixture(
        self, channels: list[str], timeout: float
    ) -> tuple[tuple[float | None, ...], float]:
        """Wait up to ``timeout`` for the robot at rest at the fixture (see :meth:`zero`);
        the rest levels it rests at, and since when. Raises NotAtFixture with what is
        awaited."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while not self.travel.at_fixture(channels):
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise NotAtFixture(
                        f"Could not zero yet: {self.travel.waiting_sentence(channels)}.",
                        tuple(channels),
                    )
                self._changed.wait(remaining)
            levels = tuple(self.travel.resting(c) for c in channels)
            return levels, self.travel.rest_start(channels)

    def _refuse_away(
        self,
        taken: Mapping[str, list[GaugeReading]],
        channels: list[str],
        rests: tuple[float | None, ...] | None,
    ) -> None:
        """Refuse a zero read at the indicators' stop, or (``rests``: the rest levels the robot
        was waited for at) one whose readings did not all come from that rest."""
        at_stop = self.travel.at_stop(
            {c: values[-1].device_value for c, values in taken.items() if values}
        )
        if at_stop:
            raise NotAtFixture(
                f"Could not zero: {at_stop_sentence(at_stop)}; zero once it rests there.",
                at_stop,
            )
        if rests is None:
            return
        with self._changed:
            left = [
                c
                for c, rest in zip(channels, rests, strict=True)
                if self.travel.resting(c) != rest or not self.travel.at_fixture([c])
            ]
        if left:
            raise NotAtFixture(
                f"Could not zero: the robot left the fixture while the zero was read "
                f"({', '.join(left)}); the zero is taken at its next rest there.",
                tuple(left),
            )

    def _zero_command(self, channel: str) -> bytes | None:
        reader = self._reader_of[channel]
        device_channel = next(
            d for d in reader.device_channels if reader.station_channel(d) == channel
        )
        return reader.protocol.zero_command(device_channel)

    def _apply_zeros(
        self,
        zeros: Iterable[ChannelZero],
        commands: Mapping[str, bytes | None],
        timeout: float,
    ) -> None:
        """Send the device zero commands and set the software offsets."""
        deadline = time.monotonic() + timeout
        for zero in zeros:
            reader = self._reader_of[zero.channel]
            command = commands[zero.channel]
            if zero.method == "device" and command:
                # A short dropout is waited out, as a capture waits for it.
                if not reader.wait_connected(max(0.0, deadline - time.monotonic())):
                    raise StationError(
                        f"Could not zero {zero.channel}: {reader.down_message()}. Check the "
                        "cable and try again."
                    )
                reader.send(command)
                reader.set_zero_offset(zero.channel, 0.0)
                with self._changed:
                    # The device now sends readings less its zero: what was learned moves too.
                    self.travel.shift(zero.channel, zero.mean)
            else:
                reader.set_zero_offset(zero.channel, zero.offset)

    def _zero_once(
        self,
        wanted: list[str],
        commands: Mapping[str, bytes | None],
        timeout: float,
        unit: str | None,
    ) -> list[ChannelZero]:
        """The zero from one reading: a device zero reads nothing, a software zero one set."""
        deadline = time.monotonic() + timeout
        zeros = {c: ChannelZero(c, "device", 0.0, 0) for c in wanted if commands[c]}
        software = [c for c in wanted if not commands[c]]
        if software:
            result = self.capture(max(0.0, deadline - time.monotonic()))
            absent = [c for c in software if c not in result.readings]
            if absent:
                why = result.message.rstrip(".") or "timeout"
                raise StationError(
                    f"Could not zero {', '.join(absent)}: no fresh reading arrived ({why}). "
                    "Check the gauges and try again."
                )
            if unit is not None:
                mismatch = unit_mismatch(result.readings, software, unit)
                if mismatch:
                    raise StationError(f"Could not zero: {mismatch}.")
            if result.at_stop:
                raise NotAtFixture(
                    f"Could not zero: {at_stop_sentence(result.at_stop)}; zero once it rests "
                    "there.",
                    result.at_stop,
                )
            for channel in software:
                value = result.readings[channel].device_value
                zeros[channel] = ChannelZero(
                    channel, "software", value, 1, value, 0.0, (value,), self.resolution[channel]
                )
        ordered = [zeros[c] for c in wanted]
        self._apply_zeros(ordered, commands, max(0.0, deadline - time.monotonic()))
        return ordered

    def collect(
        self,
        channels: Iterable[str] | None = None,
        readings: int = 10,
        settle: float = 1.0,
        timeout: float = 2.0,
        *,
        since: float | None = None,
    ) -> dict[str, list[GaugeReading]]:
        """Read ``channels`` until each has ``readings`` readings and ``settle`` seconds have
        passed (or ``settle`` + ``timeout`` seconds, whichever first); the readings by channel.

        A polled port is asked every ``settle / (readings − 1)`` seconds (never faster than
        every 10 ms, no input flushed, one request in flight); a pushing port is listened to
        (a streaming device sends by itself; a DATA button must be pressed ``readings``
        times). With the ``arrival`` trigger the streaming thread's polls count too. Only
        readings that arrive after the call count, or with ``since`` (a monotonic time) those
        received from then on (the settle window counts from then too)."""
        wanted = list(self.channels if channels is None else channels)
        collector: dict[str, list[GaugeReading]] = {c: [] for c in self.channels}
        interval = max(0.01, settle / max(readings - 1, 1))
        start = time.monotonic()
        deadline = start + settle + timeout
        if since is not None:
            start = min(start, since)
            with self._changed:
                for channel in self.channels:
                    collector[channel] = [r for r in self._history[channel] if r.t_mono >= since]
        polled = {self._reader_of[c] for c in wanted if self._reader_of[c].protocol.polled}
        in_flight: dict[GaugeReader, TriggerTicket] = {}
        with self._changed:
            self._collectors.append(collector)
        try:
            next_poll = start
            while True:
                now = time.monotonic()
                with self._changed:
                    enough = all(len(collector[c]) >= readings for c in wanted)
                if (enough and now - start >= settle) or now >= deadline:
                    break
                if now >= next_poll and not (
                    self._stream_thread and self.poll_interval <= interval
                ):
                    for reader in polled:
                        ticket = in_flight.get(reader)
                        if reader.state == "connected" and (ticket is None or ticket.done.is_set()):
                            in_flight[reader] = reader.trigger(True, flush=False)
                    next_poll = now + interval
                with self._changed:
                    self._changed.wait(max(0.0, min(next_poll, deadline) - time.monotonic()))
        finally:
            with self._changed:
                self._collectors.remove(collector)
        return {c: list(collector[c]) for c in wanted}
