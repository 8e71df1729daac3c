"""Run rules: for every rule of every set, a sequence that just triggers it and one that just
does not (centre 0, sigma 1, so the 1/2/3-sigma lines are at +-1, +-2, +-3)."""

import pytest

from station.analysis.rules import RULE_SETS, Alarm, check_rules, rule_descriptions
from station.errors import StationError

RISING_7 = [-0.6, -0.4, -0.2, 0.0, 0.2, 0.4, 0.6]
ZIGZAG_15 = [-0.5, 0.5] * 7 + [-0.5]

# rule id -> (sequence that triggers, the points it flags, sequence that just does not).
CASES = {
    "report-1": ([0.0, 3.01], {2}, [0.0, 3.0, -3.0]),
    "report-2": (RISING_7, {7}, RISING_7[:3] + [RISING_7[2]] + RISING_7[4:]),
    "report-3": (ZIGZAG_15, {15}, ZIGZAG_15[:14]),
    "report-4": ([0.0, 2.1, 0.0, 2.1], {4}, [0.0, 2.1, 0.0, 0.0, 2.1, -2.1, 2.0]),
    "we-1": ([0.0, -3.01], {2}, [0.0, 3.0, -3.0]),
    "we-2": ([0.0, -2.1, -2.1], {3}, [0.0, 2.1, -2.1, 0.0, 2.1]),
    "we-3": ([0.0, 1.1, 1.1, 0.0, 1.1, 1.1], {6}, [1.1, 1.1, 0.0, 0.0, 1.1, 1.1, 1.0, 1.0]),
    "we-4": ([0.1] * 8, {8}, [0.1] * 7 + [0.0] + [0.1] * 7),
    "nelson-1": ([3.01, 0.0], {1}, [3.0, -3.0]),
    "nelson-2": ([-0.1] * 9, {9}, [-0.1] * 8 + [0.1]),
    "nelson-3": (RISING_7[::-1][:6], {6}, RISING_7[:5] + [RISING_7[4]]),
    "nelson-4": (ZIGZAG_15[:14], {14}, ZIGZAG_15[:13]),
    "nelson-5": ([2.1, 0.0, 2.1], {3}, [2.1, 0.0, 0.0, 2.1]),
    "nelson-6": ([-1.1, -1.1, -1.1, 0.0, -1.1], {5}, [-1.1, -1.1, -1.1, 0.0, 1.1]),
    "nelson-7": ([0.3] * 14 + [1.0], {15}, [0.3] * 14 + [1.01]),
    "nelson-8": ([1.1, -1.1] * 4, {8}, [1.1, -1.1] * 3 + [1.1, -1.0]),
}


def flagged(points, rule_id):
    rule_set = {"report": "report", "we": "western-electric", "nelson": "nelson"}[
        rule_id.split("-")[0]
    ]
    alarms = check_rules(points, 0.0, 1.0, rule_set)
    return {p for alarm in alarms if alarm.rule == rule_id for p in alarm.points}


def test_every_rule_has_a_case():
    ids = {rule_id for rule_set in RULE_SETS for rule_id, _ in rule_descriptions(rule_set)}
    assert ids == set(CASES)
    assert len(ids) == 4 + 4 + 8


@pytest.mark.parametrize("rule_id", sorted(CASES))
def test_rule_just_triggers(rule_id):
    triggering, expected, _ = CASES[rule_id]
    assert flagged(triggering, rule_id) == expected


@pytest.mark.parametrize("rule_id", sorted(CASES))
def test_rule_just_does_not_trigger(rule_id):
    _, _, quiet = CASES[rule_id]
    assert flagged(quiet, rule_id) == set()


def test_trends_and_runs_flag_every_point_that_extends_them():
    assert flagged(RISING_7 + [0.8, 0.9], "report-2") == {7, 8, 9}
    assert flagged([0.1] * 10 + [-0.1], "we-4") == {8, 9, 10}


def test_alarms_group_contiguous_points_on_one_side_and_say_where():
    alarms = check_rules(
        [0.0, 3.5, 3.6, 0.0, -3.2], 0.0, 1.0, "western-electric", unit="in", resolution=0.1
    )
    beyond = [a for a in alarms if a.rule == "we-1"]
    assert beyond == [
        Alarm(
            "we-1",
            (2, 3),
            "Points 2 and 3 are above the upper control limit (+3.00 in): "
            "look for a cause at those cycles.",
        ),
        Alarm(
            "we-1",
            (5,),
            "Point 5 is below the lower control limit (-3.00 in): look for a cause at that cycle.",
        ),
    ]


def test_the_report_example_sentence():
    """The control line in the one number format (issue 22): signed, one decimal beyond the
    0.0001 in gauge step, as every other figure (it was ``0.00081``, unsigned)."""
    sigma = 0.00027
    points = [0.0001] * 14 + [0.0009]
    alarms = check_rules(points, 0.0, sigma, unit="in", resolution=0.0001)
    (alarm,) = [a for a in alarms if a.rule == "report-1"]
    assert alarm.text == (
        "Point 15 is above the upper control limit (+0.00081 in): look for a cause at that cycle."
    )


def test_pattern_alarms_name_the_pattern_and_the_direction():
    (alarm,) = check_rules([0.1] * 9, 0.0, 1.0, "nelson", resolution=0.01)
    assert alarm.rule == "nelson-2"
    assert alarm.text.startswith(
        "Point 9 completes 9 points in a row above the centre line (+0.000)"
    )
    assert "shifted up" in alarm.text
    falling = check_rules(RISING_7[::-1] + [-0.8], 0.0, 1.0, "report")
    assert [a.rule for a in falling] == ["report-2"]
    assert falling[0].text.startswith("Points 7 and 8 each end 7 points in a row, each lower")


def test_alarms_are_ordered_by_first_point():
    alarms = check_rules([0.0, 2.5, 2.5, 3.5], 0.0, 1.0, "western-electric")
    assert [(a.rule, a.points) for a in alarms] == [("we-2", (3, 4)), ("we-1", (4,))]


def test_no_limits_means_nothing_to_check():
    assert check_rules([1.0, 2.0], None, None) == []
    assert check_rules([], 0.0, 1.0) == []


def test_unknown_rule_set_lists_the_known_ones():
    with pytest.raises(StationError, match="use one of report, western-electric, nelson"):
        check_rules([0.0], 0.0, 1.0, "minitab")
    with pytest.raises(StationError, match="unknown rule set"):
        rule_descriptions("we")


def test_bad_sigma_or_points_are_refused():
    with pytest.raises(StationError, match="sigma must be"):
        check_rules([0.0], 0.0, -1.0)
    with pytest.raises(StationError, match="point 2 is not a number"):
        check_rules([0.0, float("nan")], 0.0, 1.0)


def test_descriptions_are_one_line_each():
    for rule_set in RULE_SETS:
        for rule_id, text in rule_descriptions(rule_set):
            assert "\n" not in text and text.endswith(".") and rule_id
    assert [rid for rid, _ in rule_descriptions("report")] == [
        "report-1",
        "report-2",
        "report-3",
        "report-4",
    ]


def test_sentences_are_written_when_read_not_when_found(monkeypatch):
    """A long record raises thousands of alarms; their sentences cost more than finding them,
    so check_rules writes none, and each alarm writes its own once, when it is read."""
    from station.analysis import rules

    written = []
    original = rules._Kind.text

    def counted(self, *args):
        written.append(args[0])
        return original(self, *args)

    monkeypatch.setattr(rules._Kind, "text", counted)
    alarms = check_rules([3.5, -3.5] * 500, 0.0, 1.0, "nelson")
    assert len(alarms) > 1000 and written == []
    first = alarms[0].text
    assert alarms[0].text == first and written == ["Point 1"]
    assert first == (
        "Point 1 is above the upper control limit (+3.000000): look for a cause at that cycle."
    )


def test_a_deferred_sentence_is_the_sentence_given_as_text():
    (found,) = [a for a in check_rules([0.0, 3.5, 3.6], 0.0, 1.0, "report") if a.rule == "report-1"]
    given = Alarm("report-1", (2, 3), found.text)
    assert found == given and hash(found) == hash(given)
    assert repr(found) == repr(given)
    with pytest.raises(AttributeError):
        found.rule = "report-2"  # type: ignore[misc]
