"""``station history`` over simulated sessions with a growing bias, and ``station baseline``."""

from __future__ import annotations

import json
import os
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest

from station.cli import main
from station.errors import StationError
from station.record.baseline import baseline_for, baseline_path, clear_baseline, store_baseline
from station.record.history import robot_history, text_chart, threshold_crossing

from .conftest import write_repeatability

START = datetime(2026, 1, 5, 9, 0, tzinfo=UTC)
STEP_DAYS = 30
BIAS_STEP = 0.0001  # x drifts 0.0001 in per 30 days: its Cpk reaches 1 on day 120


def five_sessions(folder, robot="KSC-7"):
    paths = []
    for index in range(5):
        paths.append(
            write_repeatability(
                folder,
                robot=robot,
                seed=100 + index,
                bias={"x": BIAS_STEP * index},
                created=START + timedelta(days=STEP_DAYS * index),
                reject=None,
                alarm=False,
            )
        )
    # Another robot's session in the same folder is not part of the history.
    write_repeatability(folder, robot="other", seed=9, created=START)
    return paths


def test_history_shows_the_wear_trend_and_its_crossing_date(sessions, capsys):
    # x's Cpk is (0.001 − bias)/(3 × 0.0002): 1.67 on day 0, the threshold 1 on day 120, the last
    # session's. The date is Cpk's reaching the threshold with its range (it once was the mean's
    # reaching the USL, on day 300, when half the returns are out: the bug of issue 20).
    paths = five_sessions(sessions)
    history = robot_history(sessions, "KSC-7")
    assert [e.path for e in history.entries] == paths
    trends = {t.channel: t for t in history.trends}
    x = trends["x"]
    assert x.significant and x.ci_low > 0
    assert x.slope_per_day * STEP_DAYS == pytest.approx(BIAS_STEP, rel=0.35)
    assert x.cpk_significant and x.cpk_ci_high < 0 and x.threshold == 1.0
    expected = (START + timedelta(days=120)).strftime("%Y-%m-%d")
    assert x.crossing_low <= expected <= x.crossing_high
    assert x.crossing_low <= x.crossing <= x.crossing_high
    for axis in ("y", "z"):
        assert not trends[axis].cpk_significant and trends[axis].crossing is None

    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    out = capsys.readouterr().out
    assert "History of robot KSC-7 (5 sessions)" in out
    assert (
        f"the trend line crossed the threshold 1.00 on {x.crossing} "
        f"(95% range {x.crossing_low} to {x.crossing_high}) and is below it now" in out
    )
    assert "RP over the sessions" in out and "Cpk of x over the sessions" in out
    assert "y: Cpk shows no significant trend" in out and "USL" not in out

    assert main(["history", "KSC-7", "--sessions", str(sessions), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert [s["file"] for s in document["sessions"]] == [p.name for p in paths]
    assert document["trends"][0]["crossing"] == x.crossing
    assert document["trends"][0]["crossing_range"] == [x.crossing_low, x.crossing_high]
    offsets = [s["channels"]["x"]["offset"] for s in document["sessions"]]
    assert offsets == sorted(offsets) or offsets[-1] > offsets[0] + 0.0003


def test_history_dates_when_cpk_will_reach_the_threshold_with_a_range(sessions, capsys):
    """x's bias grows 0.00003 in a month: its Cpk, (0.001 − bias)/0.0006, reaches 1 on day 400,
    after the last session (day 270). The date comes with a range that holds the true one;
    y and z, unchanged, have no significant trend and no date."""
    for k in range(10):
        write_repeatability(
            sessions,
            seed=200 + k,
            bias={"x": 0.00003 * k},
            cycles=60,
            created=START + timedelta(days=STEP_DAYS * k),
            reject=None,
            alarm=False,
        )
    trends = {t.channel: t for t in robot_history(sessions, "KSC-7").trends}
    x = trends["x"]
    true = (START + timedelta(days=400)).strftime("%Y-%m-%d")
    last = (START + timedelta(days=270)).strftime("%Y-%m-%d")
    assert x.cpk_significant and last < x.crossing
    assert x.crossing_low <= true <= x.crossing_high
    assert x.sentence.startswith(
        f"x: Cpk falls {abs(x.cpk_slope_per_day) * 30:.2f} per 30 days (95% CI "
    )
    assert (
        f"at this rate it reaches the threshold 1.00 on {x.crossing} "
        f"(95% range {x.crossing_low} to {x.crossing_high})." in x.sentence
    )
    for axis in ("y", "z"):
        flat = trends[axis]
        assert not flat.cpk_significant and flat.crossing is None
        assert flat.crossing_low is None and flat.crossing_high is None
        assert flat.sentence.startswith(f"{axis}: Cpk shows no significant trend (95% CI ")
        assert "no date is given" in flat.sentence


def test_threshold_crossing_is_where_the_confidence_band_holds_the_threshold():
    from scipy import stats

    days = np.array([0.0, 30, 60, 90, 120, 150])
    cpk = np.array([1.9, 1.75, 1.72, 1.5, 1.48, 1.3])
    day, low, high = threshold_crossing(days, cpk, 1.0)
    fit = stats.linregress(days, cpk)
    assert fit.intercept + fit.slope * day == pytest.approx(1.0)
    # Brute force: the days whose band (t on 4 dof) contains 1.0.
    grid = np.linspace(-200, 1000, 120001)
    n, mean = days.size, days.mean()
    s2 = ((cpk - fit.intercept - fit.slope * days) ** 2).sum() / (n - 2)
    half = stats.t.ppf(0.975, n - 2) * np.sqrt(
        s2 * (1 / n + (grid - mean) ** 2 / ((days - mean) ** 2).sum())
    )
    inside = grid[np.abs(fit.intercept + fit.slope * grid - 1.0) <= half]
    assert low == pytest.approx(inside.min(), abs=0.02)
    assert high == pytest.approx(inside.max(), abs=0.02)
    # A slope the interval does not tell from 0 gives no date at all.
    assert threshold_crossing(days, [1.5, 1.9, 1.4, 1.8, 1.45, 1.7], 1.0) is None
    assert threshold_crossing(days[:2], cpk[:2], 1.0) is None


def test_history_of_an_unknown_robot_says_so(sessions, capsys):
    write_repeatability(sessions, robot="KSC-7")
    assert main(["history", "KSC-8", "--sessions", str(sessions)]) == 2
    assert "no session of robot 'KSC-8'" in capsys.readouterr().err


def test_text_chart_places_the_extremes_on_the_top_and_bottom_rows():
    lines = text_chart([1.0, 2.0, None, 3.0], height=4)
    assert lines[0].endswith("*") and lines[0].strip().startswith("3")
    assert "*" in lines[3] and lines[3].strip().startswith("1")
    assert len(lines) == 5


def test_baseline_is_stored_loaded_marked_and_cleared(sessions, capsys):
    paths = five_sessions(sessions)
    assert baseline_for("KSC-7") is None
    # The second session is capable by the report's rule but INCONCLUSIVE on y: no baseline.
    assert main(["baseline", "KSC-7", str(paths[1])]) == 2
    assert "not shown CAPABLE on y (INCONCLUSIVE" in capsys.readouterr().err
    assert main(["baseline", "KSC-7", str(paths[0])]) == 0
    record = baseline_for("KSC-7")
    assert record is not None
    assert set(record["channels"]) == {"x", "y", "z"}
    x = record["channels"]["x"]
    assert x["lcl"] < x["center"] < x["ucl"] and x["mr_ucl"] > 0
    assert record["anchor"] in paths[0].read_text()
    assert baseline_path("KSC-7").parent.parent.parent == Path(os.environ["XDG_DATA_HOME"])

    history = robot_history(sessions, "KSC-7")
    assert [e.baseline for e in history.entries] == [True, False, False, False, False]
    capsys.readouterr()
    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    assert capsys.readouterr().out.count("[baseline]") == 1

    assert main(["baseline", "KSC-7"]) == 0
    assert record["session"] in capsys.readouterr().out
    assert main(["baseline", "KSC-7", "--clear"]) == 0
    assert baseline_for("KSC-7") is None
    assert not clear_baseline("KSC-7")


def test_a_baseline_must_be_finished_capable_and_of_that_robot(sessions):
    capable = write_repeatability(sessions, robot="R1")
    from station.errors import StationError

    with pytest.raises(StationError, match="not 'R2'"):
        store_baseline("R2", capable)
    wide = write_repeatability(sessions, robot="R1", seed=4, noise={"y": 0.0008})
    with pytest.raises(StationError, match="not capable on y"):
        store_baseline("R1", wide)
    unfinished = sessions / "unfinished.jsonl"
    lines = capable.read_bytes().splitlines(keepends=True)
    unfinished.write_bytes(b"".join(lines[:-1]))  # without its finish event
    with pytest.raises(StationError, match="not finished"):
        store_baseline("R1", unfinished)
    assert baseline_for("R1") is None


def test_a_damaged_baseline_is_named_not_trusted(sessions, capsys):
    store_baseline("R1", write_repeatability(sessions, robot="R1"))
    baseline_path("R1").write_text("{not json")
    assert main(["baseline", "R1"]) == 2
    assert "cannot be read" in capsys.readouterr().err


def test_a_baseline_is_never_written_through_a_symbolic_link(sessions, tmp_path):
    filed = write_repeatability(sessions, robot="R1")
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    link = baseline_path("R1")
    link.parent.mkdir(parents=True, exist_ok=True)
    link.symlink_to(victim)
    with pytest.raises(StationError, match="symbolic link"):
        store_baseline("R1", filed)
    assert victim.read_text() == "precious\n" and link.is_symlink()
    assert sorted(p.name for p in link.parent.iterdir()) == [link.name]  # no temporary left


def test_a_link_planted_beside_the_baseline_neither_blocks_nor_receives_it(sessions, tmp_path):
    """The baseline's temporary file has an unpredictable name: a link planted at the name the
    store once used (``.<file>.<pid>.partial``) is left alone and the baseline is stored."""
    filed = write_repeatability(sessions, robot="R1")
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    path = baseline_path("R1")
    path.parent.mkdir(parents=True, exist_ok=True)
    planted = path.with_name(f".{path.name}.{os.getpid()}.partial")
    planted.symlink_to(victim)
    store_baseline("R1", filed)
    assert baseline_for("R1")["robot"] == "R1"
    assert path.is_file() and not path.is_symlink()
    assert victim.read_text() == "precious\n" and planted.is_symlink()


def test_history_names_each_file_it_could_not_read_in_one_line(sessions, capsys):
    """Issue 27, finding 9: a folder with corrupt files among a robot's sessions. The history
    is the readable sessions; each corrupt file is one line saying why, in the text and the
    JSON, never left out silently."""
    paths = five_sessions(sessions)
    (sessions / "garbage.jsonl").write_bytes(b"\x00\xffnot a session\n" * 50)
    torn = sessions / "cut-in-its-header.jsonl"
    torn.write_bytes(paths[0].read_bytes()[:40])
    (sessions / "empty.jsonl").write_bytes(b"")

    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    out = capsys.readouterr().out
    assert "History of robot KSC-7 (5 sessions)" in out
    assert "Left out (3 files that could not be read):" in out
    lines = {line.split(":")[0].strip(): line for line in out.splitlines() if ".jsonl:" in line}
    assert set(lines) >= {"garbage.jsonl", "cut-in-its-header.jsonl", "empty.jsonl"}
    for name in ("garbage.jsonl", "cut-in-its-header.jsonl", "empty.jsonl"):
        assert len(lines[name].split(": ", 1)[1]) > 10, lines[name]  # a reason, not a bare name

    assert main(["history", "KSC-7", "--sessions", str(sessions), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert sorted(s["file"] for s in document["skipped"]) == [
        "cut-in-its-header.jsonl",
        "empty.jsonl",
        "garbage.jsonl",
    ]
    assert all(s["error"] for s in document["skipped"])
    assert len(document["sessions"]) == 5


def test_a_short_session_is_provisional_in_the_history_as_in_its_report(sessions, capsys):
    """Fewer readings than the verdict needs: the history says PROVISIONAL with the count, as
    the session's own report does, never UNDEFINED (which means no limits)."""
    from station.analysis.verdict import DEFAULT_MIN_N

    write_repeatability(sessions, robot="KSC-7", seed=4, cycles=DEFAULT_MIN_N - 5, reject=None)
    (entry,) = robot_history(sessions, "KSC-7").entries
    assert entry.verdict == f"PROVISIONAL: {DEFAULT_MIN_N - 5} of {DEFAULT_MIN_N}"


def test_an_inconclusive_session_is_no_baseline_and_the_refusal_says_what_settles_it(
    sessions, capsys
):
    """Baseline policy (issue 20): capable by the report's rule (Cpk >= 1) but INCONCLUSIVE by
    its Bissell bounds is refused, naming the bounds and the readings that would settle it;
    nothing is stored. A CAPABLE session of the same robot is then accepted."""
    from station.record.source import analyse_session

    wide = write_repeatability(sessions, robot="R1", noise={"x": 0.00027}, seed=4)
    channel = analyse_session(wide).report.analysis.channels["x"]
    verdict = channel.verdict
    assert channel.capability.capable is True and verdict.word == "INCONCLUSIVE"
    assert verdict.readings_needed is not None
    assert main(["baseline", "R1", str(wide)]) == 2
    said = capsys.readouterr().err
    assert "not shown CAPABLE on x (INCONCLUSIVE: Cpk" in said
    assert f"bounds {verdict.lower:.2f} to {verdict.upper:.2f} straddle 1" in said
    assert f"a session of {verdict.readings_needed} readings on x (at this Cpk)" in said
    assert len(said.strip().splitlines()) == 1
    assert baseline_for("R1") is None
    assert store_baseline("R1", write_repeatability(sessions, robot="R1"))["robot"] == "R1"
