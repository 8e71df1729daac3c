"""``stroke``: stream readings while the robot moves along the bar (linearity).

Every complete set is a point and every point is written, in ``samples`` events numbered by
stroke (one per ``batch_seconds`` or ``batch_points``, so the fsync cost stays bounded). With
:meth:`StrokeStep.stream` the strokes are split live by the travel of the step's direction
channel (:class:`~station.analysis.strokes.TravelTracker`, with the deadband recorded in the
session header); the last event of a whole stroke carries ``end: true`` and the batch analysis
takes those strokes as they are. A lead-in (the robot was moving when streaming began) or a
stroke cut short keeps its own number without the mark, and the analysis leaves it out.
"""

from __future__ import annotations

import queue
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from station.analysis.strokes import TravelTracker, stroke_deadband
from station.errors import StationError
from station.procedures import Step, StepSchema
from station.run.state import Action, Progress, StrokeOutcome
from station.run.steps.base import PlanItem, StepHandler

if TYPE_CHECKING:
    from station.run.engine import Runner
    from station.run.setup import SessionSetup

STILL_SECONDS = 2.0
"""How long the scale must rest at an end for a stroke to close there."""


def stroke_counts(setup: SessionSetup, step: Step) -> tuple[int, int]:
    """(target, minimum) whole strokes of a stroke step: the set-up's count, when it gives one,
    is the target and bounds the minimum."""
    target = int(setup.strokes or step.count_target or 1)
    return target, min(int(step.count_min or target), target)


class StrokeStep(StepHandler):
    """Done by the operator's confirm once its minimum of whole strokes is streamed."""

    kind = "stroke"
    schema = StepSchema(channels=True, counts=True, direction=True)

    def header_fields(self, setup: SessionSetup, step: Step) -> Mapping[str, Any]:
        return {
            # One deadband rule, recorded: the live split and any later re-split use this value.
            "deadband": stroke_deadband(setup.resolved_resolution),
            # A linearity verdict is final from the strokes the procedure's step asks for at
            # least (a trial run the set-up shortens stays provisional, as a short run of
            # cycles does).
            "strokes_min": int(step.count_min or step.count_target or 1),
        }

    def counts(self, run: Runner, item: PlanItem) -> tuple[int, int]:
        """(target, minimum) strokes (the set-up's count when it gives one)."""
        return stroke_counts(run.setup, item.step)

    def whole_strokes(self, run: Runner, item: PlanItem) -> int:
        """Whole strokes recorded in the step."""
        return int(run.step_state(item).get("strokes", 0))

    def action(self, run: Runner, item: PlanItem) -> Action:
        target, minimum = self.counts(run, item)
        done = self.whole_strokes(run, item)
        prompt = (
            f"All {target} strokes are recorded: go on, or finish."
            if done >= target
            else self.prompt(run, item)
        )
        return Action("stream", prompt=prompt, may_confirm=done >= minimum)

    def progress(self, run: Runner, item: PlanItem) -> Progress:
        target, minimum = self.counts(run, item)
        under_way = int(run.step_state(item).get("points", 0))
        return Progress(self.whole_strokes(run, item), target, minimum, "stroke", under_way)

    def confirm(self, run: Runner, item: PlanItem, by: str) -> None:
        done = self.whole_strokes(run, item)
        target, minimum = self.counts(run, item)
        if run.busy:
            raise StationError("a stroke is under way: end it first")
        if done < minimum:
            raise StationError(
                f"only {done} of {target} strokes are recorded; record at least "
                f"{minimum - done} more before going on"
            )
        run.complete_step(item, by)

    def replay(self, run: Runner, item: PlanItem, event: Mapping[str, Any]) -> None:
        if event.get("type") != "samples":
            return
        state = run.step_state(item)
        number = int(event.get("stroke") or 0)
        state["numbers"] = max(int(state.get("numbers", 0)), number)
        if event.get("end") or not run.stroke_marks:
            # A file from before the end marks: every number is a stroke.
            if event.get("end"):
                state["strokes"] = int(state.get("strokes", 0)) + 1
            else:
                state["strokes"] = max(int(state.get("strokes", 0)), number)

    # -- streaming ----------------------------------------------------------------------------

    def stream(
        self,
        run: Runner,
        item: PlanItem,
        *,
        timeout: float = 1.0,
        deadband: float | None = None,
        still_seconds: float = STILL_SECONDS,
        batch_seconds: float = 0.25,
        batch_points: int = 200,
        on_stroke: Callable[[StrokeOutcome], object] | None = None,
        by: str = "operator",
    ) -> int:
        """Stream the step's channels and split the strokes by the travel of its direction
        channel as they happen, until the step has its target of whole strokes,
        :meth:`~station.run.engine.Runner.end_stroke`, or the session stops. Returns the whole
        strokes recorded in the step so far."""
        state = run.step_state(item)
        with run.lock:
            run.ensure_running()
            run.claim()
            run.stop_stream.clear()
            pushed = run.setup.trigger == "push"
            stream_queue = run.open_stream_queue() if pushed else None
        channels = list(item.step.channels)
        scale = channels.index(str(item.step.direction_channel))
        target, _ = self.counts(run, item)
        recorded_deadband = run.header.get("deadband")
        tracker = TravelTracker(
            deadband
            if deadband is not None
            else float(recorded_deadband or stroke_deadband(run.setup.resolved_resolution)),
            still_seconds=still_seconds,
        )
        # Points of the segment under way: written in batches, the whole segment kept until it
        # closes (one stroke's worth) for the per-stroke figure and the live analysis.
        segment: list[tuple[list[float], float]] = []
        written = number = skipped = 0
        flushed_at = time.monotonic()

        def open_segment() -> None:
            nonlocal number, written, segment
            with run.lock:
                number = int(state.get("numbers", 0)) + 1
                state["numbers"] = number
            segment, written = [], 0

        def flush(end: bool = False, last: bool = False) -> None:
            nonlocal written, flushed_at
            # Keep the last point back until the segment ends (or streaming does), so its end
            # mark always comes with at least one point.
            upto = len(segment) if end or last else len(segment) - 1
            if upto > written:
                rows = [row for row, _ in segment[written:upto]]
                stamps = [stamp for _, stamp in segment[written:upto]]
                self._write_samples(run, item, number, channels, rows, stamps, by, end=end)
                written = upto
            flushed_at = time.monotonic()

        def next_result() -> Any:
            if stream_queue is not None:
                try:
                    return stream_queue.get(timeout=timeout)
                except queue.Empty:
                    return None
            return run.gauges.capture(timeout)

        open_segment()
        try:
            while not run.stop_stream.is_set() and run.status == "running":
                with run.lock:
                    if self.whole_strokes(run, item) >= target:
                        break
                result = next_result()
                if result is None:
                    continue
                if run.set_problem(result, channels):
                    skipped += 1
                    continue
                row = [float(result.readings[ch].value) for ch in channels]
                stamp = max(result.readings[ch].t_mono for ch in channels)
                for event in tracker.add((row, stamp), row[scale], stamp):
                    if event.kind == "points":
                        segment.extend(event.points)
                        continue
                    flush(end=event.stroke, last=True)
                    if event.stroke:
                        self._stroke_done(run, item, number, segment, channels, event, on_stroke)
                    open_segment()
                state["points"] = len(segment)
                if (
                    len(segment) - written >= batch_points
                    or time.monotonic() - flushed_at >= batch_seconds
                ):
                    flush()
            segment.extend(tracker.flush())
            if run.status == "running":
                flush(last=True)  # a segment still open: recorded, without the end mark
        finally:
            with run.lock:
                run.close_stream_queue()
                run.release()
                state["points"] = 0
        if skipped:
            run.say("warning", f"{skipped} incomplete reading sets were skipped.")
        with run.lock:
            return self.whole_strokes(run, item)

    def _stroke_done(
        self,
        run: Runner,
        item: PlanItem,
        number: int,
        segment: Sequence[tuple[list[float], float]],
        channels: Sequence[str],
        event: Any,
        on_stroke: Callable[[StrokeOutcome], object] | None,
    ) -> None:
        state = run.step_state(item)
        with run.lock:
            count = int(state.get("strokes", 0)) + 1
            state["strokes"] = count
            target, _ = self.counts(run, item)
        profile = {
            channel: tuple(row[index] for row, _ in segment)
            for index, channel in enumerate(channels)
        }
        outcome = StrokeOutcome(
            stroke=number,
            points=len(segment),
            skipped=0,
            message=f"Stroke {count} of {target} ({event.direction}): {len(segment)} points.",
            direction=event.direction,
            count=count,
            profile=profile,
        )
        run.stroke_recorded(outcome)
        run.say("info", outcome.message)
        if on_stroke is not None:
            on_stroke(outcome)

    def _write_samples(
        self,
        run: Runner,
        item: PlanItem,
        number: int,
        channels: Sequence[str],
        rows: Sequence[Sequence[float]],
        stamps: Sequence[float],
        by: str,
        *,
        end: bool,
    ) -> None:
        """One ``samples`` event of stroke ``number`` (``end``: the stroke's last points)."""
        with run.lock:
            run.ensure_open()
            run.append(
                "samples",
                step=item.step.id,
                placement=item.placement,
                stroke=number,
                channels=list(channels),
                values=[list(row) for row in rows],
                t_mono=list(stamps),
                by=by,
                end=True if end else None,
            )
