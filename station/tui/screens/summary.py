"""The summary: the verdict per axis and overall (PROVISIONAL below the minimum count, the Cpk
with the digits that agree with the word), readings out of specification, the 3-D figures, the
alarms (recorded live with their acknowledgements, and the retrospective chart's, each marked),
the hints (drift, autocorrelation, non-normal data among them), the file and its hash, and the
exports (the text report and CSV) into the sessions folder.

It shows the analysis the runner returned on finish, or, when reviewing, the analysis of a saved
session; the words and figures come from the analysis and the report module, unchanged.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Group
from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import VerticalScroll
from textual.screen import Screen
from textual.widgets import Static

from station.analysis.report import budget_line
from station.analysis.rules import rule_name
from station.analysis.verdict import confidence_text
from station.errors import StationError
from station.session.durable import write_text_durably
from station.session.export import export_csv
from station.session.model import load_session
from station.text import (
    CAPABLE,
    INCONCLUSIVE,
    NOT_CAPABLE,
    format_figure,
    format_index,
    judged_count,
    judged_cpk,
    judged_word,
    overall_judgement,
    zero_taken,
)
from station.tui.remedies import explained
from station.tui.screens.dialogs import HelpScreen
from station.tui.text import shown, shown_line
from station.tui.theme import VERDICT_STYLES
from station.tui.widgets.key_footer import KeyFooter

if TYPE_CHECKING:
    from station.run import RunnerState
    from station.tui.app import StationApp


@dataclass(frozen=True)
class SummaryView:
    """What the summary shows."""

    path: Path
    header: Mapping[str, Any]
    analysis: Any
    last_hash: str
    status: str
    cycle_numbers: tuple[int, ...] = ()
    excluded_cycles: tuple[int, ...] = ()
    notes: tuple[str, ...] = field(default_factory=tuple)
    report: Any = None
    """The session's report by its method (``station.methods.SessionReport``): its
    ``analysis`` is what the capability verdict judges, its ``verdict`` the method's own (a
    gauge study's), its blocks the method's report."""

    @classmethod
    def from_live(cls, state: RunnerState, analysis: Any, header: Mapping[str, Any]) -> SummaryView:
        """After ``finish``: the runner's final state and analysis."""
        report, notes = _procedure_report(state.path, header)
        return cls(
            path=state.path,
            header=dict(header),
            # The method's judgement of the file; the live analysis only when there is none.
            analysis=report.analysis if report is not None and not report.empty else analysis,
            last_hash=state.last_hash,
            status=state.status,
            cycle_numbers=tuple(r.cycle for r in state.cycles if r.rejected is None),
            excluded_cycles=tuple(r.cycle for r in state.cycles if r.rejected is not None),
            notes=notes,
            report=report,
        )

    @classmethod
    def from_file(cls, path: Path) -> SummaryView:
        """A saved session, read-only (the file is not changed, not even a torn tail)."""

        session = load_session(path, recover=False)
        report, notes = _procedure_report(path, session.header, session)
        analysis = report.analysis if report is not None else None
        if session.torn is not None:
            notes = (*notes, session.torn.message)
        return cls(
            path=path,
            header=dict(session.header),
            analysis=analysis,
            last_hash=session.last_hash,
            status=session.status,
            cycle_numbers=session.accepted_cycles,
            excluded_cycles=session.excluded_cycles,
            notes=notes,
            report=report,
        )

    @property
    def verdict_word(self) -> str:
        """The verdict's first word as a list shows it: the method's own (ACCEPTABLE), else
        the overall capability judgement (PROVISIONAL below the minimum count)."""
        own = getattr(self.report, "verdict", None)
        if own is not None:
            return str(own.word)
        channels = getattr(self.analysis, "channels", {}) or {}
        return overall_judgement(channels.values()).partition(":")[0]

    @property
    def unit(self) -> str:
        """The session's unit."""
        return str(self.header.get("unit", ""))

    @property
    def resolution(self) -> float | None:
        """The gauge's step (every figure is written at one decimal beyond it)."""
        resolution = self.header.get("resolution")
        return float(resolution) if resolution else None


REPORT_WIDTH = 74
"""The procedure's report block fits the summary's column at 80×24 (scrollbar and padding)."""


def _procedure_report(
    path: Path, header: Mapping[str, Any], session: Any = None
) -> tuple[Any, tuple[str, ...]]:
    """The session's report as its method makes it (the verdict, and for methods with a report
    block of their own, that block), and a note saying why there is none when the file has
    nothing to analyse yet. ``session``: the file already loaded."""
    # Deferred: the methods load numpy (on a worker while the screens before it show).
    from station.methods import load_session_source, report_session, session_source

    try:
        source = load_session_source(path) if session is None else session_source(session)
        zero = zero_taken(source.session.zeroes, header.get("resolution"))
        return report_session(source, width=REPORT_WIDTH), (zero,) if zero else ()
    except StationError as error:
        return None, (error.message,)


def report_text(view: SummaryView) -> Text:
    """The procedure's own report block (straightness per stroke and path repeatability, or
    accuracy per placement and across placements), as ``station analyze FILE`` prints it."""
    if view.report is None:
        return Text("")
    return shown("\n".join(view.report.lines), no_wrap=True, overflow="crop")


def one_sided_sentence(capability: Any, resolution: float | None, unit: str) -> str:
    """Why Cp shows "—" beside a Cpk: a limit on one side only (the straightness of a stroke,
    never below 0, against its tolerance) is judged one-sided; "" for two-sided limits."""
    lsl = getattr(capability, "lsl", None)
    usl = getattr(capability, "usl", None)
    if (lsl is None) == (usl is None):
        return ""
    if usl is not None:
        return (
            f"one-sided: upper limit {format_figure(usl, resolution)} {unit} only; "
            "Cpk = (USL − X̄)/3σ, Cp needs two limits."
        )
    return (
        f"one-sided: lower limit {format_figure(lsl, resolution)} {unit} only; "
        "Cpk = (X̄ − LSL)/3σ, Cp needs two limits."
    )


def verdict_text(view: SummaryView) -> Text:
    """The verdict block: overall, then one line per axis with Cp, Cpk and the reason, and the
    readings out of specification."""
    analysis = view.analysis
    text = Text()
    own = getattr(view.report, "verdict", None)
    if analysis is None and own is not None:
        # A method with a verdict of its own (a gauge linearity study): its word and why.
        text.append("Verdict: ", style="bold")
        text.append(own.word, style=VERDICT_STYLES.get(own.word, ""))
        text.append(f"\n  {shown_line(own.sentence, limit=None)}\n")
        return text
    if analysis is None and view.report is not None and not view.report.empty:
        # A kind that judges no readings (a gain schedule): its report block is the result.
        return Text("No capability verdict: this procedure judges no readings (its report below).")
    if analysis is None:
        return Text("No accepted cycles: there is nothing to judge yet.", style="bold yellow")
    overall = overall_judgement(analysis.channels.values())
    text.append("Verdict: ", style="bold")
    text.append(overall, style=VERDICT_STYLES.get(overall.partition(":")[0], ""))
    threshold = analysis.config.threshold
    level = confidence_text(analysis.config.confidence)
    text.append(
        f"   (capable when Cpk's {level} lower bound ≥ {threshold:g}; (lower–upper) its "
        f"one-sided {level} bounds, Bissell; {judged_count(analysis)}; unit {view.unit})\n",
        style="dim",
    )
    for name, channel in analysis.channels.items():
        word = judged_word(channel)
        capability = channel.capability
        descriptive = channel.descriptive
        bounds = (
            f"{format_index(capability.cpk_lower)}–{format_index(capability.cpk_upper)}"
            if capability.cpk_lower is not None and capability.cpk_upper is not None
            else format_index(None)
        )
        text.append(f"  {shown_line(name, limit=20)}  ", style="bold")
        # The word alone: the verdict line above says how many of how many (the axes share
        # it), so the axis' figures fit one line at 80 columns ("σ" was left alone at its end).
        text.append(f"{word:<12}", style=VERDICT_STYLES.get(word, ""))
        text.append(
            f" Cp {format_index(capability.cp)}  Cpk {judged_cpk(channel)} ({bounds})"
            f"  X̄ {format_figure(descriptive.mean, view.resolution)}"
            f"  σ {format_figure(descriptive.sd, view.resolution, signed=False)}\n"
        )
        verdict = channel.verdict
        if verdict is not None and word in (INCONCLUSIVE, CAPABLE, NOT_CAPABLE):
            # Why the word, and the report's own rule beside it (issue 20).
            settle = (
                f"{verdict.readings_needed} readings settle it; "
                if verdict.readings_needed is not None
                else ""
            )
            text.append(f"    {settle}{verdict.rule_text}\n", style="dim")
        if channel.budget is not None:
            # The U the readings' decisions took, so the figure shown is the figure used.
            line = budget_line(
                channel.budget, channel.reading_decisions, view.resolution, view.unit
            )
            text.append(f"      {line}\n", style="dim")
        if word == "UNDEFINED" and capability.message:
            text.append(f"      {shown_line(capability.message, limit=None)}\n", style="yellow")
        one_sided = one_sided_sentence(capability, view.resolution, view.unit)
        if one_sided:
            text.append(f"      {one_sided}\n")
        found = channel.out_of_spec
        if found is not None and found.total:
            cycles = ", ".join(str(c) for c in found.cycles)
            text.append(
                f"      out of specification: {found.total} reading"
                f"{'s' if found.total > 1 else ''} ({found.below} below the LSL, {found.above} "
                f"above the USL), cycle{'s' if found.total > 1 else ''} {cycles}\n",
                style="bold red",
            )
    return text


def alarms_text(view: SummaryView) -> Text:
    """The alarms: those recorded while capturing (live, against the frozen limits) with their
    acknowledgements, and those of the retrospective chart (limits from every reading), each
    rule named in words and marked live or retrospective."""

    text = Text("Alarms\n", style="bold")
    recorded = tuple(getattr(view.report, "recorded_alarms", None) or ())
    if recorded:
        text.append(f"  recorded while capturing ({len(recorded)}):\n")
        for alarm in recorded:
            where = "live" if alarm.live else "retrospective"
            text.append(
                f"  #{alarm.seq} {shown_line(alarm.channel, limit=20)}, "
                f"{shown_line(alarm.rule_name, limit=None)} [{where}]: "
                f"{shown_line(alarm.text, limit=None)}\n"
            )
            if alarm.acks:
                text.append(
                    f"      acknowledged: {shown_line(alarm.acks[-1].describe(), limit=None)}\n",
                    style="green",
                )
            else:
                text.append("      not acknowledged\n", style="yellow")
    else:
        text.append("  none recorded while capturing\n", style="dim")
    channels = getattr(view.analysis, "channels", {}) or {}
    retrospective = [
        (name, alarm, channel.alarm_is_live(alarm))
        for name, channel in channels.items()
        for alarm in getattr(channel, "alarms", ()) or ()
    ]
    if retrospective:
        text.append(f"  retrospective chart (limits from every reading, {len(retrospective)}):\n")
        for name, alarm, live in retrospective:
            mark = "live and retrospective" if live else "retrospective only"
            text.append(
                f"  {shown_line(name, limit=20)}, {rule_name(alarm.rule)} [{mark}]: "
                f"{shown_line(alarm.text, limit=None)}\n"
            )
    return text


def spatial_text(view: SummaryView) -> Text:
    """The 3-D figures: offsets from nominal, the report's total, ISO 9283 RP and AP."""
    spatial = getattr(view.analysis, "spatial", None)
    if spatial is None:
        return Text("")
    resolution = view.resolution
    text = Text("3-D\n", style="bold")
    offsets = "  ".join(
        f"{axis} {format_figure(v, resolution)}" for axis, v in spatial.offset.items()
    )
    text.append(f"  offset from nominal: {offsets} {view.unit}\n")
    text.append(
        f"  total offset √(Σ offset²) (ISO 9283 APp): "
        f"{format_figure(spatial.total_offset, resolution, signed=False)} {view.unit}\n"
    )
    text.append(
        f"  ISO 9283 pose repeatability RP = l̄ + 3·S_l: "
        f"{format_figure(spatial.rp, resolution, signed=False)} {view.unit}\n"
    )
    if spatial.message:
        text.append(f"  {spatial.message}\n", style="yellow")
    return text


def hints_text(view: SummaryView) -> Group | Text:
    """The report's hints about what the figures point to, as a bulleted list."""
    hints = tuple(getattr(view.analysis, "hints", ()) or ())
    if not hints:
        return Text("")
    table = Table.grid(padding=(0, 1))
    table.add_column(width=3, justify="right")
    table.add_column(ratio=1)
    for hint in hints:
        table.add_row("•", shown(hint))
    return Group(Text("What the figures suggest", style="bold"), table)


def file_text(view: SummaryView, exported: list[str]) -> Text:
    """Where the session file is, its status and the hash that anchors it."""
    text = Text("Session file\n", style="bold")
    text.append(f"  {shown_line(view.path, limit=None)}\n")
    text.append(f"  status {view.status}; last line hash (write it on the filed report):\n")
    text.append(f"  {view.last_hash}\n")
    if view.excluded_cycles:
        cycles = ", ".join(str(c) for c in view.excluded_cycles)
        text.append(f"  rejected cycles, left out of the analysis: {cycles}\n")
    for note in view.notes:
        text.append(f"  {shown_line(note, limit=None)}\n", style="yellow")
    for line in exported:
        text.append(f"  {shown_line(line, limit=None)}\n", style="green")
    return text


def _trimmed(text: Text) -> Text:
    """The text without its last newline (the blocks are spaced by CSS)."""
    text.rstrip()
    return text


class SummaryScreen(Screen[None]):
    """The verdict, the figures behind it, and the exports."""

    BINDINGS = [
        Binding("e", "export_report", "Export report"),
        Binding("c", "export_csv", "Export CSV"),
        Binding("d", "dashboard", "Charts"),
        Binding("h", "home", "Home"),
        Binding("f1", "help", "Help"),
        Binding("q", "quit", "Quit"),
        Binding("escape", "back", "Back", show=False),
    ]

    app: StationApp

    def __init__(self, view: SummaryView, *, reviewing: bool = False) -> None:
        super().__init__()
        self.view = view
        self.reviewing = reviewing
        self.exported: list[str] = []

    def compose(self) -> ComposeResult:
        """The blocks in a scrolling column."""
        header = self.view.header
        procedure = header.get("procedure") or {}
        title = Text("Summary", style="bold")
        title.append(
            f"  robot {shown_line(header.get('robot', '?'), limit=60)} · "
            f"{shown_line(procedure.get('id', ''), limit=40)} · operator "
            f"{shown_line(header.get('operator') or 'not given', limit=60)} · "
            + (
                (self.view.report.count if self.view.report is not None else None)
                or f"{len(self.view.cycle_numbers)} cycles"
            ),
        )
        yield Static(title, id="summary-title")
        with VerticalScroll(id="summary-body"):
            yield Static(_trimmed(verdict_text(self.view)), id="summary-verdict")
            yield Static(_trimmed(spatial_text(self.view)), id="summary-spatial")
            yield Static(_trimmed(alarms_text(self.view)), id="summary-alarms")
            report = Static(report_text(self.view), id="summary-report")
            report.display = self.view.report is not None and bool(self.view.report.sections)
            yield report
            yield Static(hints_text(self.view), id="summary-hints")
            yield Static(file_text(self.view, self.exported), id="summary-file")
        # Exports and refusals are said on this line, not in toasts over the verdict.
        yield Static("", id="summary-message")
        yield KeyFooter()

    def notify(
        self, message: str, *, severity: str = "information", markup: bool = True, **_: Any
    ) -> None:
        """Say ``message`` on the summary's own message line (a toast would cover the
        summary's text); errors in bold, as words, not only a colour."""
        style = {"error": "bold red", "warning": "bold yellow"}.get(severity, "green")
        prefix = {"error": "Error: ", "warning": "Warning: "}.get(severity, "")
        self.query_one("#summary-message", Static).update(shown(prefix + message, style=style))

    def _refresh_file(self) -> None:
        self.query_one("#summary-file", Static).update(file_text(self.view, self.exported))

    def _export_path(self, suffix: str) -> Path:
        """Beside the session file, named after it: never a path from user input."""
        return self.view.path.with_name(self.view.path.stem + suffix)

    def action_export_report(self) -> None:
        """The filed report (the same as ``station report FILE``: robot, operator, procedure,
        gauges, zero, limits, every reading, notes, alarms, verdicts, anchor, sign-off) beside
        the session file, as text and as a self-contained HTML page with its charts."""
        from station.record.render import render_reports  # deferred: it loads numpy

        try:
            reports = render_reports(self.view.path, ("txt", "html"))
            text, page = reports["txt"], reports["html"]
        except StationError as error:
            self.notify(shown_line(explained(error), limit=None), severity="error", markup=False)
            return
        txt, html = self._export_path(".report.txt"), self._export_path(".report.html")
        if self._write(txt, text, "report") and self._write(html, page, "HTML report"):
            # One line, whole: the files are named after the session file (its block above
            # lists their full paths); a path cut at the screen's edge said nothing.
            self.notify("Report filed beside the session file, as .report.txt and .report.html")

    def action_export_csv(self) -> None:
        """Every cycle as tidy CSV (rejected ones marked) beside the session file."""

        try:
            session = load_session(self.view.path, recover=False)
        except StationError as error:
            self.notify(shown_line(explained(error), limit=None), severity="error", markup=False)
            return
        buffer = io.StringIO()
        export_csv(session, buffer)
        target = self._export_path(".csv")
        if self._write(target, buffer.getvalue(), "CSV"):
            self.notify("CSV filed beside the session file, as .csv")

    def _write(self, target: Path, content: str, what: str) -> bool:
        """Write an export beside the session file; False (and a sentence) when refused."""

        try:
            # Never through a link planted at the export's name, never over the session file.
            write_text_durably(target, content, not_over=self.view.path)
        except StationError as error:
            self.notify(shown_line(explained(error), limit=None), severity="error", markup=False)
            return False
        except OSError as error:
            self.notify(
                shown_line(f"could not write {target}: {error.strerror}", limit=None),
                severity="error",
                markup=False,
            )
            return False
        self.exported.append(f"{what} exported to {target}")
        self._refresh_file()
        return True

    def action_dashboard(self) -> None:
        """The statistics table and charts of this session, read-only."""
        # Deferred: a screen loads when first shown.
        from station.tui.screens.dashboard import DashboardScreen, review_view, session_title

        header = self.view.header
        resolution = header.get("resolution")
        cycles = len(self.view.cycle_numbers)
        self.app.push_screen(
            DashboardScreen(
                live=False,
                view=review_view(
                    session_title(header),
                    tuple(header.get("channels") or ()),
                    self.view.analysis,
                    self.view.cycle_numbers,
                    resolution=float(resolution) if resolution else None,
                    unit=str(header.get("unit", "")),
                    progress=f"{cycles} accepted cycles, {self.view.status}",
                    alarms=getattr(self.view.report, "recorded_alarms", None),
                ),
            )
        )

    def action_home(self) -> None:
        """Back to the home screen."""
        self.app.go_home()

    def action_back(self) -> None:
        """Reviewing: back to the list; after a session: home."""
        if self.reviewing:
            self.app.pop_screen()
        else:
            self.app.go_home()

    def action_help(self) -> None:
        """The keys."""

        self.app.push_screen(HelpScreen())

    def action_quit(self) -> None:
        """Leave the program (the session is already saved)."""
        self.app.exit(0)
