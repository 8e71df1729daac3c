"""The assignable causes a procedure offers when an alarm is acknowledged."""

from __future__ import annotations

import pytest
from helpers import CHECK_STEP as CHECK
from helpers import PROBE_HEAD as HEAD
from helpers import write_procedure as write

from station.errors import StationError
from station.procedures import DEFAULT_CAUSES, load_procedure


def test_a_procedure_without_causes_offers_the_default_list(tmp_path):
    procedure = load_procedure(write(tmp_path, HEAD + CHECK))
    assert procedure.causes == DEFAULT_CAUSES
    assert DEFAULT_CAUSES == ("fixture moved", "gauge", "temperature", "robot", "other")


def test_a_procedure_names_its_own_causes_and_other_is_always_offered(tmp_path):
    text = HEAD + 'causes = ["air pressure", "gauge "]\n' + CHECK
    assert load_procedure(write(tmp_path, text)).causes == ("air pressure", "gauge", "other")


@pytest.mark.parametrize(
    ("causes", "fault"),
    [
        ("[]", "'causes' must be a list"),
        ('"gauge"', "'causes' must be a list"),
        ('["gauge", "gauge"]', "names 'gauge' twice"),
        ('["", "gauge"]', "give one line of text"),
        ('["a\\nb"]', "give one line of text"),
        ("[3]", "give one line of text"),
    ],
)
def test_bad_causes_name_the_file_and_the_fault(tmp_path, causes, fault):
    with pytest.raises(StationError, match=fault) as caught:
        load_procedure(write(tmp_path, HEAD + f"causes = {causes}\n" + CHECK))
    assert "probe.toml" in str(caught.value)
