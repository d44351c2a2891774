"""The objective and limit grammar (refinement.objective_grammar): what parses, what each parse means, and the
column and reason of every malformed input; the binding's [objective] table and the API's arguments."""

from __future__ import annotations

import pytest
from tailor.errors import ArgumentTypeError, ArgumentValueError, BindingError
from tailor.refinement.binding import parse_binding
from tailor.refinement.objective_grammar import (
    DURATION_ONLY,
    MAX_TEXT,
    MeasureBound,
    ObjectiveSyntaxError,
    WeightedObjective,
    bounds_of,
    objective_from_table,
    parse_bound,
    parse_objective,
    tokenize,
)


@pytest.mark.parametrize("text, weights", [
    ("duration", (("duration", 1.0),)),
    ("duration + 0.3*energy", (("duration", 1.0), ("energy", 0.3))),
    ("energy*2+duration", (("energy", 2.0), ("duration", 1.0))),  # either way round, any spacing
    ("  2 * duration  +  .5 * error ", (("duration", 2.0), ("error", 0.5))),
    ("1e-3*energy + duration", (("energy", 0.001), ("duration", 1.0))),
    ("duration + 0.25*energy + 0.5*energy", (("duration", 1.0), ("energy", 0.75))),  # a measure twice: summed
    ("0*energy + heading_error", (("energy", 0.0), ("heading_error", 1.0))),  # weight 0 parses, weighs nothing
    ("3.*duration", (("duration", 3.0),)),
])
def test_objectives_parse_to_their_weights(text, weights):
    objective = parse_objective(text)
    assert objective.weights == weights
    assert objective.measures == tuple(m for m, w in weights if w > 0)


def test_an_objective_is_written_back_in_the_grammar_and_reparses_to_itself():
    objective = parse_objective("energy*0.3 + duration")
    assert objective.text() == "0.3*energy + duration"
    assert parse_objective(objective.text()) == objective
    assert parse_objective("duration") == DURATION_ONLY and DURATION_ONLY.plain
    assert not objective.plain and objective.weight("energy") == 0.3 and objective.weight("error") == 0.0
    assert objective.to_json() == {"energy": 0.3, "duration": 1.0}


@pytest.mark.parametrize("text, col, message", [
    ("", 1, "expected a measure or a number, found the end"),
    ("duration +", 11, "expected a measure or a number, found the end"),
    ("duration + + energy", 12, "expected a measure or a number, found '+'"),
    ("duration energy", 10, "expected '+' or the end, found a measure 'energy'"),
    ("3 energy", 3, "expected '*' after a weight, found a measure 'energy'"),
    ("duration*energy", 10, "expected a number after '*', found a measure 'energy'"),
    ("2*3*energy", 3, "expected a measure after '*', found a number '3'"),
    ("0.3*", 5, "expected a measure after '*', found the end"),
    ("duration - 0.3*energy", 10, "'-': weights are >= 0"),
    ("-duration", 1, "'-': weights are >= 0"),
    ("duration + 1e999*energy", 12, "'1e999' is not a finite number"),
    ("duration / 2", 10, "unexpected character '/'"),
    ("duration + (energy)", 12, "unexpected character '('"),
    ("__import__('os')", 11, "unexpected character '('"),  # never evaluated: a name, then a stray character
    ("duration = 3", 10, "expected '+' or the end, found '='"),
])
def test_malformed_objectives_name_the_column_and_what_was_expected(text, col, message):
    with pytest.raises(ObjectiveSyntaxError) as info:
        parse_objective(text)
    assert info.value.col == col and str(info.value).startswith(f"col {col}: {message}")


def test_an_objective_that_weighs_nothing_or_is_too_long_is_refused():
    with pytest.raises(ObjectiveSyntaxError, match="every weight is 0"):
        parse_objective("0*duration + 0*energy")
    with pytest.raises(ObjectiveSyntaxError, match=f"longer than {MAX_TEXT} characters"):
        parse_objective("duration + " * 200 + "duration")
    with pytest.raises(ObjectiveSyntaxError, match="expected text"):
        tokenize(3)


@pytest.mark.parametrize("weights, message", [
    ((("energy", -0.5),), "must be a finite number >= 0"),
    ((("energy", float("inf")),), "must be a finite number >= 0"),
    ((("energy", 0.0),), "weighs no measure"),
    ((("duration", 1.0), ("duration", 2.0)), "weighed twice"),
    ((("2x", 1.0),), "not a measure's name"),
])
def test_a_weighted_objective_refuses_negative_weights_and_nonsense(weights, message):
    with pytest.raises(ValueError, match=message):
        WeightedObjective(weights)


@pytest.mark.parametrize("text, bound", [("error=0.05", MeasureBound("error", 0.05)),
                                         (" energy = 120 ", MeasureBound("energy", 120.0)),
                                         ("heading_error=0", MeasureBound("heading_error", 0.0))])
def test_limits_parse(text, bound):
    assert parse_bound(text) == bound
    assert parse_bound(bound.text()) == bound


@pytest.mark.parametrize("text, col, message", [
    ("error", 6, "expected '=' (MEASURE=NUMBER, e.g. error=0.05), found the end"),
    ("=0.05", 1, "expected a measure (MEASURE=NUMBER"),
    ("error=", 7, "expected a number (MEASURE=NUMBER"),
    ("error=-0.05", 7, "'-': a bound on a measure is >= 0"),
    ("error=0.05 m", 12, "expected the end (MEASURE=NUMBER"),
    ("error<=0.05", 6, "unexpected character '<'"),
    ("error=inf", 7, "expected a number (MEASURE=NUMBER, e.g. error=0.05), found a measure 'inf'"),
])
def test_malformed_limits_name_the_column(text, col, message):
    with pytest.raises(ObjectiveSyntaxError) as info:
        parse_bound(text)
    assert info.value.col == col and str(info.value).startswith(f"col {col}: {message}")


def test_a_measure_limited_twice_is_refused():
    assert bounds_of(["error=0.05", MeasureBound("energy", 3.0)]) == (MeasureBound("error", 0.05),
                                                                    MeasureBound("energy", 3.0))
    with pytest.raises(ObjectiveSyntaxError, match=r"error is limited twice \(0.05 and 0.1\)"):
        bounds_of(["error=0.05", "error=0.1"])


def test_the_objective_table_of_a_binding():
    assert objective_from_table({"duration": 1, "energy": 0.3}).weights == (("duration", 1.0), ("energy", 0.3))
    for table, message in (({"energy": -1}, "a weight is a finite number >= 0"), ({"energy": "0.3"}, "a weight"),
                           ({"energy": True}, "a weight"), ({"duration": 0}, "no measure has a weight above 0")):
        with pytest.raises(ValueError, match=message):
            objective_from_table(table)


SOCCER = {"schema": 2, "simulator": "soccer"}


def test_a_binding_declares_its_default_objective_checked_against_its_simulator():
    assert parse_binding(SOCCER).objective == DURATION_ONLY
    binding = parse_binding({**SOCCER, "objective": {"duration": 1.0, "energy": 0.2}}, "b.toml")
    assert binding.objective.weights == (("duration", 1.0), ("energy", 0.2))
    with pytest.raises(BindingError, match=r"^b.toml: \[objective\] 'enrgy' is not a measure of simulator 'soccer' "
                                           r"\(known: duration, energy, error, heading_error\); did you mean 'energy'"):
        parse_binding({**SOCCER, "objective": {"enrgy": 1.0}}, "b.toml")
    with pytest.raises(BindingError, match=r"^b.toml: \[objective\] energy = -1: a weight is a finite number >= 0"):
        parse_binding({**SOCCER, "objective": {"energy": -1}}, "b.toml")
    with pytest.raises(BindingError, match=r"'objective' must be a table"):
        parse_binding({**SOCCER, "objective": "duration + energy"}, "b.toml")


def test_the_api_takes_the_objective_as_text_mapping_or_object_and_limits_as_mapping_or_texts():
    from tailor.refinement.api import _objective_arguments

    text, _ = _objective_arguments("duration + 0.3*energy", None)
    table, _ = _objective_arguments({"duration": 1.0, "energy": 0.3}, None)
    assert text == table == parse_objective("duration + 0.3*energy")
    assert _objective_arguments(None, {"error": 0.05})[1] == (MeasureBound("error", 0.05),)
    assert _objective_arguments(None, ["error=0.05"])[1] == (MeasureBound("error", 0.05),)
    with pytest.raises(ArgumentValueError, match=r"objective 'duration \+': col 11: expected a measure"):
        _objective_arguments("duration +", None)
    with pytest.raises(ArgumentValueError, match="objective: energy = -1: a weight is a finite number >= 0"):
        _objective_arguments({"energy": -1}, None)
    with pytest.raises(ArgumentTypeError, match="objective must be text, a mapping"):
        _objective_arguments(3, None)
    with pytest.raises(ArgumentValueError, match="limits: the bound of error must be a finite number >= 0"):
        _objective_arguments(None, {"error": -0.1})
    with pytest.raises(ArgumentTypeError, match="limits must be a mapping"):
        _objective_arguments(None, "error=0.05")
