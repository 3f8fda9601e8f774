"""PART's decision list on Quinlan's weather data, as WEKA 3.6 prints it."""

from __future__ import annotations

import numpy as np
import pytest

from tests.benchmark.weka.test_c45 import NOMINAL, WEATHER
from touchbench.benchmark.weka import PARTClassifier

NAN = np.nan


def weather_rules() -> PARTClassifier:
    return PARTClassifier(nominal_features=NOMINAL).fit(WEATHER[:, :4], WEATHER[:, 4])


def test_wekas_decision_list_for_the_weather() -> None:
    # WEKA: "outlook = overcast: yes (4.0)", "humidity = high: no (5.0/1.0)", ": yes (5.0/1.0)"
    rules = weather_rules().rules_
    assert [[(f, b) for f, _, _, b, _ in conditions] for conditions, _ in rules] == [
        [(0, 1)],
        [(2, 0)],
        [],
    ]
    assert [counts.tolist() for _, counts in rules] == [[4.0, 0.0], [1.0, 4.0], [4.0, 1.0]]


def test_rules_apply_in_order_and_missing_values_split_a_row() -> None:
    model = weather_rules()
    rows = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 1.0, 0.0]])
    assert model.predict(rows).tolist() == [0, 1, 0]
    # outlook unknown: 4/14 of the row is covered by the first rule (yes), the rest by the
    # second (humidity high: no 4 of 5)
    proba = model.predict_proba(np.array([[NAN, 0.0, 0.0, 0.0]]))[0]
    share = 4 / 14
    expected = np.array([share * 1.0, 0.0]) + (1 - share) * np.array([1 / 5, 4 / 5])
    np.testing.assert_allclose(proba, expected / expected.sum())


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="confidence must lie in"):
        PARTClassifier(confidence=0.0).fit(np.zeros((2, 1)), [0, 1])
