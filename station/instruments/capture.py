"""Reading sets by trigger: what a capture returns, and how each trigger takes one.

A :class:`~station.instruments.gauge.GaugeSet` turns its readers' streams into reading sets by
trigger (:mod:`station.instruments.triggers` says what each means); this module takes them.

A port that is down when a capture starts is waited for until the capture's timeout (a short
dropout costs a delay, not a refused set); a channel still missing because its port stayed down
is marked ``disconnected`` in the :class:`CaptureResult`, not blamed on the gauges.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from station.instruments.arrival import ReturnTrace
from station.instruments.reader import GaugeReader, GaugeReading, TriggerTicket


@dataclass(frozen=True)
class CaptureResult:
    """One reading set: the reading per station channel and what went wrong, if anything."""

    trigger: str
    channels: tuple[str, ...]
    readings: Mapping[str, GaugeReading]
    missing: tuple[str, ...] = ()
    """Channels with no fresh reading (they are absent from ``readings``)."""
    stale: tuple[str, ...] = ()
    """Missing channels whose last reading predates the trigger (it was not taken)."""
    duplicated: tuple[str, ...] = ()
    """Channels that sent more than one reading for this set; the first one was taken."""
    errors: tuple[str, ...] = ()
    """Port problems met during the capture (a disconnected port, a failed request)."""
    t_trigger: float = 0.0
    disconnected: tuple[str, ...] = ()
    """Missing channels whose port was down for the whole wait (the set is not the gauges'
    fault: the line is reconnecting)."""
    at_stop: tuple[str, ...] = ()
    """Channels whose reading sits at the indicator's free-travel stop: the robot is away
    from the fixture, so the set measures the plungers, not the robot."""
    trace: ReturnTrace | None = None
    """An arrival set's trace of its return, when the trigger keeps traces."""

    @property
    def port_down(self) -> bool:
        """True when a channel is missing only because its port was down (not a refusal by
        the gauges: wait for the line and capture again)."""
        return bool(self.disconnected)

    @property
    def complete(self) -> bool:
        """True when every channel has a fresh reading."""
        return not self.missing

    @property
    def message(self) -> str:
        """One sentence for the operator: empty when the set is complete and clean."""
        parts = []
        if self.missing:
            fresh_less = [
                c for c in self.missing if c not in self.stale and c not in self.disconnected
            ]
            # An arrival that did not happen is said by its error, not as silent gauges.
            if fresh_less and (self.trigger != "arrival" or self.readings):
                parts.append("no reading from " + ", ".join(fresh_less))
            if self.stale:
                parts.append(
                    "only readings from before the trigger on "
                    + ", ".join(self.stale)
                    + " (not taken)"
                )
        if self.duplicated:
            parts.append(
                "more than one reading from " + ", ".join(self.duplicated) + " (the first taken)"
            )
        if self.at_stop:
            parts.append(at_stop_sentence(self.at_stop))
        parts.extend(self.errors)
        if not parts:
            return ""
        return "; ".join(parts) + "."


def at_stop_sentence(channels: Iterable[str]) -> str:
    """Why a set at the indicators' free-travel stop is no cycle, naming the channels."""
    names = ", ".join(channels)
    return (
        f"{names} read their free-travel stop: the robot is away from the fixture (bring it "
        "back to the taught point)"
    )


class SetCaptures:
    """Captures by trigger, :meth:`arm` and :meth:`wait_set` (a part of
    :class:`~station.instruments.gauge.GaugeSet`, whose attributes it uses: the readers, the
    channels and their history under the ``_changed`` condition, the pending push set)."""

    def _trigger_all(self, send_requests: bool, timeout: float) -> tuple[dict[str, float], list]:
        """Trigger every reader; the send time per station channel, and the errors.

        A port that is down (a short dropout, a device server restarting) is waited for until
        ``timeout``: the trigger goes out once it is back, so a dropout shorter than the
        timeout costs a delay, not a refused set. A port still down at the deadline is one
        error, and its channels get no send time.
        """
        deadline = time.monotonic() + timeout
        tickets = [(reader, reader.trigger(send_requests)) for reader in self.readers]
        t_sent: dict[str, float] = {}
        errors = []
        for reader, ticket in tickets:
            while True:
                ticket.done.wait(max(0.0, deadline - time.monotonic()))
                if ticket.t_sent is not None and not ticket.error:
                    break
                remaining = deadline - time.monotonic()
                if not ticket.done.is_set() or remaining <= 0 or not reader.alive:
                    break
                # Nothing was sent (the port was or went down): wait for it and trigger again.
                if not reader.wait_connected(remaining):
                    break
                ticket = reader.trigger(send_requests)
            if ticket.error or ticket.t_sent is None:
                errors.append(ticket.error or f"{reader.url} did not take the trigger in time")
                continue
            for channel in reader.channels:
                t_sent[channel] = ticket.t_sent
        return t_sent, errors

    def capture(self, timeout: float = 2.0) -> CaptureResult:
        """Take one reading set by this set's trigger, waiting at most ``timeout`` seconds.

        Only readings that arrive after the trigger count (stale input is flushed first). For
        ``push`` this arms the set now and waits for the device to send every channel.
        """
        start = time.monotonic()
        if self.trigger == "push":
            errors = self.arm(timeout)
            result = self.wait_set(max(0.0, timeout - (time.monotonic() - start)))
            if result is not None:
                return result
            with self._changed:
                partial = dict(self._pending)
            return self._result("push", partial, self._push_armed_at, {}, errors)
        if self.trigger == "arrival":
            return self._capture_arrival(timeout)
        if self.trigger == "poll":
            return self._capture_poll(timeout)
        return self._capture_stable(timeout)

    def _capture_arrival(self, timeout: float) -> CaptureResult:
        """The next arrival set after now (the robot must leave and come back to rest)."""
        start = time.monotonic()
        errors = self.arm(timeout)
        result = self.wait_set(max(0.0, timeout - (time.monotonic() - start)))
        if result is not None:
            return result
        waiting = {
            "waiting": "the robot did not leave the fixture",
            "away": "the robot did not come back",
            "returned": "the robot came back but did not settle",
        }[self.arrival_state or "waiting"]
        return CaptureResult(
            "arrival",
            self.channels,
            {},
            missing=self.channels,
            errors=(*errors, f"{waiting} within {timeout:g} s"),
            t_trigger=start,
            disconnected=tuple(c for c in self.channels if self._reader_of[c].state != "connected"),
        )

    def _capture_poll(self, timeout: float) -> CaptureResult:
        deadline = time.monotonic() + timeout
        t_sent, errors = self._trigger_all(True, timeout)
        taken: dict[str, GaugeReading] = {}
        counts: dict[str, int] = {}
        with self._changed:
            while True:
                for channel, since in t_sent.items():
                    fresh = [r for r in self._history[channel] if r.t_mono >= since]
                    counts[channel] = len(fresh)
                    if fresh:
                        taken[channel] = fresh[0]
                if len(taken) == len(t_sent):
                    break
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                self._changed.wait(remaining)
        duplicated = {c: n for c, n in counts.items() if n > 1}
        t_trigger = min(t_sent.values(), default=time.monotonic())
        return self._result("poll", taken, t_trigger, duplicated, errors, t_sent)

    def _capture_stable(self, timeout: float) -> CaptureResult:
        deadline = time.monotonic() + timeout
        t_sent, errors = self._trigger_all(True, timeout)
        window = self.stable_ms / 1000.0
        next_poll = time.monotonic() + self.poll_interval
        polled = [r for r in self.readers if r.protocol.polled]
        in_flight: dict[GaugeReader, TriggerTicket] = {}
        taken: dict[str, GaugeReading] = {}
        while True:
            with self._changed:
                taken = {}
                for channel, since in t_sent.items():
                    chosen = self._stable_reading(channel, since, window)
                    if chosen is not None:
                        taken[channel] = chosen
            if t_sent and len(taken) == len(t_sent):
                break
            now = time.monotonic()
            if now >= deadline:
                break
            if now >= next_poll:
                for reader in polled:
                    # No flush (earlier answers still count) and no pile-up of requests.
                    if reader not in in_flight or in_flight[reader].done.is_set():
                        in_flight[reader] = reader.trigger(True, flush=False)
                next_poll = now + self.poll_interval
            with self._changed:
                self._changed.wait(min(deadline, next_poll) - time.monotonic())
        t_trigger = min(t_sent.values(), default=time.monotonic())
        return self._result("stable", taken, t_trigger, {}, errors, t_sent)

    def _stable_reading(self, channel: str, since: float, window: float) -> GaugeReading | None:
        """The latest reading when ``channel`` has stayed within k × resolution for the window."""
        fresh = [r for r in self._history[channel] if r.t_mono >= since]
        if not fresh:
            return None
        latest = fresh[-1]
        band = self.stable_k * self.resolution[channel] + 1e-12
        low = high = latest.value
        for reading in reversed(fresh):
            low = min(low, reading.value)
            high = max(high, reading.value)
            if high - low > band:
                return None
            if latest.t_mono - reading.t_mono >= window:
                return latest
        return None

    def _result(
        self,
        trigger: str,
        taken: Mapping[str, GaugeReading],
        t_trigger: float,
        duplicated: Mapping[str, int],
        errors: Iterable[str],
        t_sent: Mapping[str, float] | None = None,
    ) -> CaptureResult:
        missing = tuple(c for c in self.channels if c not in taken)
        stale = []
        disconnected = tuple(
            c
            for c in missing
            if self._reader_of[c].state != "connected" or (t_sent is not None and c not in t_sent)
        )
        with self._changed:
            for channel in missing:
                if channel in disconnected:
                    continue
                history = self._history[channel]
                since = (t_sent or {}).get(channel, t_trigger)
                if history and history[-1].t_mono < since:
                    stale.append(channel)
        return CaptureResult(
            trigger,
            self.channels,
            dict(taken),
            missing=missing,
            stale=tuple(stale),
            duplicated=tuple(c for c in self.channels if c in duplicated),
            errors=tuple(errors),
            t_trigger=t_trigger,
            disconnected=disconnected,
            at_stop=self.at_stop(taken),
        )

    def arm(self, timeout: float = 1.0) -> list[str]:
        """Push: forget partial and completed sets and buffered input; later readings count.
        Arrival: the same, and only a departure after now starts a cycle.

        Returns the port problems met (empty when every port took the trigger). Call it when
        the operator is asked to press DATA, then :meth:`wait_set`.
        """
        _, errors = self._trigger_all(False, timeout)
        with self._changed:
            self._push_armed_at = time.monotonic()
            self._pending.clear()
            self._pending_duplicated.clear()
            self._sets.clear()
            if self._detector is not None:
                # Only a departure after this counts: a robot already back is not a cycle.
                self._detector.reset()
        return errors

    def read_units(self, timeout: float = 2.0) -> dict[str, str]:
        """Take one reading set (by this set's trigger) and return the unit each channel reads
        in (channels that sent nothing are absent): check it against the session's unit before
        a session starts."""
        return {channel: r.unit for channel, r in self.capture(timeout).readings.items()}

    def wait_set(self, timeout: float) -> CaptureResult | None:
        """The next completed push set, or None when none completes within ``timeout``."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while not self._sets:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self._changed.wait(remaining)
            return self._sets.popleft()
