"""``station report``: one content model in txt, md and html; the HTML opened in a real headless
Chromium, the Markdown in a standard parser."""

from __future__ import annotations

import io
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest
from helpers import start_simulator, stop_simulator

from station.cli import main
from station.record.content import MISSING, acknowledgement_of, build_content
from station.record.render import render_report
from station.record.source import analyse_session

from .conftest import (
    write_accuracy,
    write_gauge_check,
    write_joints,
    write_linearity,
    write_repeatability,
)

CHROMIUM = shutil.which("chromium-headless-shell")
BUILDERS = {
    "repeatability": write_repeatability,
    "relative_accuracy": write_accuracy,
    "linearity": write_linearity,
}
# A session of each procedure with a capability analysis (the verdict the overall block states).
CAPABILITY_BUILDERS = {
    **BUILDERS,
    "gauge_check": write_gauge_check,
    "joint_troubleshooting": write_joints,
}
# Charts each demo session draws: histogram + control chart per judged channel, then the 3-D
# offsets and drift (x, y, z sessions) or one profile chart per indicator (linearity).
EXPECTED_CHARTS = {"repeatability": 8, "relative_accuracy": 8, "linearity": 6}


class _Text(HTMLParser):
    """The visible text of an HTML page (style and SVG left out)."""

    def __init__(self) -> None:
        super().__init__()
        self.parts: list[str] = []
        self.skip = 0

    def handle_starttag(self, tag, attrs):
        if tag in ("style", "svg", "script"):
            self.skip += 1

    def handle_endtag(self, tag):
        if tag in ("style", "svg", "script"):
            self.skip -= 1

    def handle_data(self, data):
        if not self.skip:
            self.parts.append(data)


def visible_text(html: str) -> str:
    parser = _Text()
    parser.feed(html)
    return " ".join(" ".join(parser.parts).split())


def markdown_html(markdown: str) -> str:
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark").enable("table").render(markdown)


def run_station(*args: str) -> int:
    return main(list(args))


def chromium(url: str, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            CHROMIUM,
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
            *extra,
            url,
        ],
        capture_output=True,
        text=True,
        timeout=90,
    )


def console_messages(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if ":CONSOLE" in line]


def bluish_pixels(png: Path) -> int:
    """Pixels of the charts' blue (points, bars): tables and text have none."""
    from matplotlib.image import imread

    image = imread(png)
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    return int(((blue - red > 0.25) & (blue > 0.5) & (green < 0.8)).sum())


@pytest.fixture(scope="module")
def artefacts(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Where the screenshots go (kept with pytest's temporary folders for a look after)."""
    return tmp_path_factory.mktemp("report-artefacts")


@pytest.mark.slow  # a real browser
@pytest.mark.skipif(CHROMIUM is None, reason="chromium-headless-shell is not installed")
@pytest.mark.parametrize("kind", list(BUILDERS))
def test_html_report_opens_in_chromium_with_its_charts(kind, sessions, artefacts):
    path = BUILDERS[kind](sessions)
    page = sessions / f"{kind}.html"
    assert run_station("report", str(path), "--format", "html", "-o", str(page)) == 0
    html = page.read_text(encoding="utf-8")
    assert html.count("<svg") == EXPECTED_CHARTS[kind]
    assert "http://" not in html.replace("http://www.w3.org/", "")  # self-contained

    shot = artefacts / f"{kind}.png"
    result = chromium(page.as_uri(), f"--screenshot={shot}", "--window-size=1000,5000")
    assert shot.exists(), result.stderr
    assert console_messages(result.stderr) == []
    assert bluish_pixels(shot) > 5000, f"no charts visible in {shot}"

    dom = chromium(page.as_uri(), "--dump-dom").stdout
    assert dom.count('class="chart"') == EXPECTED_CHARTS[kind]


@pytest.mark.slow  # a real browser
@pytest.mark.skipif(CHROMIUM is None, reason="chromium-headless-shell is not installed")
def test_chromium_check_sees_a_page_that_reaches_outside(tmp_path):
    """The console check above can fail: a page loading an outside image is reported."""
    page = tmp_path / "outside.html"
    template = render_report(write_repeatability(tmp_path / "s", cycles=5), "html")
    page.write_text(template.replace("</body>", '<img src="http://192.0.2.1/x.png"></body>'))
    result = chromium(page.as_uri(), "--dump-dom")
    assert console_messages(result.stderr)


def facts(content) -> list[str]:
    """What every format must say, as the content model formats it."""
    said = [
        content.robot,
        content.operator,
        content.procedure_id,
        content.procedure_version,
        content.procedure_sha256,
        content.session_id,
        content.anchor,
        content.created,
        content.duration,
        f"{len(content.readings)} cycles, {len(content.rejected)} rejected",
    ]
    said += [content.overall, content.overall_basis]
    for verdict in content.verdicts:
        said += [verdict.name, verdict.word, verdict.mean, verdict.sd, verdict.cpk]
        said += [verdict.cpk_lower, verdict.cpk_upper, verdict.confidence, verdict.decision]
    for block in content.statistics:
        said.append(block.heading)
        said += [f"{label} {value}" for label, value in block.figures]
        said += [line.strip() for line in block.lines if line.strip()]
    for budget in content.budgets:
        said += [cell for row in budget.rows for cell in row]
        said += [budget.summary, budget.decisions]
    for row in content.readings:
        said += [*row.values, row.status]
    said += [f"Rejected cycle {cycle}: {reason}" for cycle, reason in content.rejected]
    said += [note.text for note in content.notes]
    said += [alarm.text for alarm in content.alarms]
    said += [value for _, value in content.figures]
    said += [zero.offset for zero in content.zeroes]
    said += [limit.usl for limit in content.limits]
    said += [gauge.port for gauge in content.gauges]
    said += list(content.hints)
    said += [line.strip() for section in content.sections for line in section if line.strip()]
    return said


def _same_words(text: str) -> str:
    """Text with its whitespace collapsed and the text report's ``LABEL: value`` pairs read as
    the tables' ``LABEL value`` cells."""
    return " ".join(re.sub(r":(?=\s|$)", " ", text).split())


@pytest.mark.parametrize("kind", list(CAPABILITY_BUILDERS))
def test_txt_md_html_say_the_same(kind, sessions):
    """Every format carries the same facts, the overall verdict block (each channel's word,
    Cpk and its Bissell bounds, the session's word) and the text report's full statistics."""
    path = CAPABILITY_BUILDERS[kind](sessions)
    content = build_content(analyse_session(path))
    texts = {
        "txt": render_report(path, "txt"),
        "md": visible_text(markdown_html(render_report(path, "md"))),
        "html": visible_text(render_report(path, "html")),
    }
    expected = [_same_words(fact) for fact in facts(content)]
    assert len(expected) > 40
    assert content.verdicts and content.statistics
    assert content.overall != MISSING
    for fmt, text in texts.items():
        said = _same_words(text)
        missing = [fact for fact in expected if fact not in said]
        assert missing == [], f"{fmt} lacks {missing[:5]}"
        # The verdict at the top, the statistics with skewness and normality in each format.
        said = said.lower()
        top = said.index(_same_words(f"verdict {content.overall}".lower()))
        readings = said.index(f"readings ({len(content.readings)} cycles")
        assert top < readings and "bissell" in said[top:readings]
        assert "skewness a1" in said and "normality" in said
    # The same number of rejected readings in each.
    assert len({text.count("rejected: ") for text in texts.values()}) == 1


def test_markdown_renders_in_a_standard_parser(sessions):
    path = write_repeatability(sessions, robot="<script>alert(1)</script> *bold* | pipe")
    html = markdown_html(render_report(path, "md"))
    assert html.count("<table>") >= 4  # facts, limits, readings, alarms, verdicts
    assert re.search(r"<h1>BASIC STATISTICS", html)
    assert "<script>" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt; *bold* | pipe" in html
    assert "<em>" not in html.split("</table>")[0]  # the name is no emphasis


def test_html_keeps_a_hostile_robot_name_as_text(sessions):
    path = write_repeatability(sessions, robot='<script>alert("x")</script>', operator="a&b")
    html = render_report(path, "html")
    assert "<script>" not in html
    assert "&lt;script&gt;alert(&#34;x&#34;)&lt;/script&gt;" in html
    assert "a&amp;b" in html


def test_control_characters_are_made_visible(sessions):
    path = write_repeatability(sessions, note="red \x1b[31mALARM\x1b[0m \u202eevil")
    for fmt in ("txt", "md", "html"):
        text = render_report(path, fmt)
        assert "\x1b" not in text and "\u202e" not in text
        assert "\\x1b[31mALARM" in text.replace("\\\\", "\\").replace("\\[", "[")
        assert "\\u202eevil" in text


def test_report_command_writes_refuses_and_chooses_the_format(sessions, capsys):
    path = write_repeatability(sessions, cycles=6)
    out = sessions.parent / "report.md"
    assert run_station("report", str(path), "-o", str(out)) == 0
    assert out.read_text().startswith("# BASIC STATISTICS")  # the suffix chose md
    assert run_station("report", str(path), "-o", str(out)) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert run_station("report", str(path), "-o", str(path), "--force") == 2
    assert "is the input file itself" in capsys.readouterr().err
    assert run_station("report", str(path), "--format", "txt") == 0
    assert capsys.readouterr().out == render_report(path, "txt")
    assert run_station("report", str(sessions / "missing.jsonl")) == 2


class _Terminal(io.StringIO):
    """Standard output that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def test_report_at_a_terminal_writes_text_and_refuses_html_in_one_line(
    sessions, capsys, monkeypatch
):
    """Issue 22: ``station report FILE --format html`` without ``-o`` wrote 170 KB of SVG to
    the terminal. There it is one line saying ``-o``; a pipe still gets the page."""
    path = write_repeatability(sessions, cycles=6)
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stdout", terminal)
    assert run_station("report", str(path)) == 0
    assert terminal.getvalue() == render_report(path, "txt")
    terminal.seek(0)
    terminal.truncate()
    assert run_station("report", str(path), "--format", "html") == 2
    assert terminal.getvalue() == ""
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "-o " in error and "terminal" in error, error
    monkeypatch.undo()
    assert run_station("report", str(path), "--format", "html") == 0
    assert capsys.readouterr().out.startswith("<!DOCTYPE html>")


def test_a_session_without_readings_still_reports(sessions):
    path = write_repeatability(sessions, cycles=0, reject=None, alarm=False)
    for fmt in ("txt", "md", "html"):
        assert "No verdict: the session has no accepted readings yet" in render_report(path, fmt)


def test_acknowledgements_are_matched_to_their_alarm():
    alarm = {"seq": 40, "channel": "x", "rule": "report-1", "cycles": [5], "t": "x"}
    by_seq = {"type": "ack", "alarm": 40, "cause": "fixture moved", "by": "ana"}
    by_seq["t"] = "2026-11-23T12:00:05.000000Z"
    by_rule = {"type": "ack", "channel": "x", "rule": "report-1", "cycles": [5, 6]}
    by_rule |= {"cause": "gauge", "action": "reseated", "t": "2026-11-23T12:00:06.000000Z"}
    other = {**by_rule, "rule": "report-4"}
    assert acknowledgement_of(alarm, [by_seq]) == "fixture moved (ana, 2026-11-23 12:00:05Z)"
    assert acknowledgement_of(alarm, [other, by_rule]).startswith("gauge; reseated")
    assert acknowledgement_of(alarm, [other]) == MISSING


def test_report_of_a_real_headless_capture(tmp_path):
    """A session recorded by ``station capture`` against ``station simulate`` (both real
    processes on a real pty) reports the same facts in every format, its port among them."""
    import os
    import sys

    station = [sys.executable, "-m", "station"]
    environment = {**os.environ, "STATION_PROCEDURES": ""}
    # Inch gauges at the procedure's 0.0001 (the frames are checked against the session).
    simulate, url = start_simulator(
        "--protocol", "mitutoyo", "--unit", "in", "--resolution", "0.0001", "--seed", "3",
        env=environment,
    )  # fmt: skip
    try:
        capture = subprocess.run(
            [
                *station, "capture", "--procedure", "repeatability", "--port", url,
                "--protocol", "mitutoyo", "--robot", "R1", "--operator", "ana",
                "--sessions", str(tmp_path / "sessions"), "--cycles", "25",
                "--trigger", "poll", "--every", "0.01",
            ],
            capture_output=True, text=True, env=environment, timeout=120,
        )  # fmt: skip
        assert capture.returncode == 0, capture.stderr
    finally:
        stop_simulator(simulate)
    (path,) = (tmp_path / "sessions").glob("*.jsonl")
    content = build_content(analyse_session(path))
    assert content.gauges[0].port == url and len(content.readings) == 25
    assert {zero.channel for zero in content.zeroes} == {"x", "y", "z"}
    texts = {
        "txt": _same_words(render_report(path, "txt")),
        "md": _same_words(visible_text(markdown_html(render_report(path, "md")))),
        "html": _same_words(visible_text(render_report(path, "html"))),
    }
    for fmt, text in texts.items():
        missing = [f for f in (_same_words(f) for f in facts(content)) if f not in text]
        assert missing == [], f"{fmt} lacks {missing[:5]}"


def test_the_text_report_names_rules_in_words_with_acks_and_a_provisional_verdict(tmp_path):
    from station.session.alarms import ack_fields
    from station.session.journal import SessionWriter
    from station.session.model import load_session

    path = write_repeatability(tmp_path / "s", cycles=9, reject=None)
    # Acknowledged before the finish, as the engine does: the finish line goes, the ack and a
    # new finish follow (the earlier lines' chain is untouched).
    lines = path.read_bytes().splitlines(keepends=True)
    path.write_bytes(b"".join(lines[:-1]))
    (alarm,) = load_session(path).alarms
    writer, _ = SessionWriter.resume(path)
    with writer:
        writer.append(
            "ack", **ack_fields(alarm["seq"], "gauge", action="re-clamped the x indicator")
        )
        writer.append("finish", by="operator", complete=True, accepted=9, rejected=[])
    text = " ".join(render_report(path, "txt").split())
    assert "report rule 1 (a point beyond the control limits) [live]" in text
    assert "acknowledged: gauge; re-clamped the x indicator" in text
    assert "PROVISIONAL: 9 of 25" in text
    assert " CAPABLE" not in text.replace("NOT CAPABLE", "")


def test_the_filed_report_shows_cpks_upper_bound_beside_the_lower(sessions):
    """INCONCLUSIVE rests on both one-sided bounds: the filed report shows both, and says they
    are Bissell's and one-sided (issue 20)."""
    path = write_repeatability(sessions, robot="bounds", noise={"x": 0.0003})
    analysis = analyse_session(path).report.analysis
    cap = analysis.channels["x"].capability
    assert cap.cpk_upper is not None and cap.cpk_lower is not None
    lower, upper = f"{cap.cpk_lower:.2f}", f"{cap.cpk_upper:.2f}"
    text = render_report(path, "txt")
    assert f"Cpk one-sided 95% bounds (Bissell): lower {lower}, upper {upper}" in text
    assert f"{lower} / {upper} (95%)" in render_report(path, "md")
    html = render_report(path, "html")
    assert "Cpk one-sided bounds, lower / upper (confidence, Bissell)" in html
    assert f"{lower} / {upper} (95%)" in html
