"""The benchmark package's messages name a parameter or a request's field (in backquotes),
never a CLI flag or command: the API returns them as they are."""

from __future__ import annotations

import re
from collections.abc import Callable

import numpy as np
import pytest

from tests.support.problems import make_problem as make
from touchbench.benchmark.catalogue import get_spec
from touchbench.benchmark.catalogue.pipeline import check_sequence_input
from touchbench.benchmark.catalogue.stacking import check_top_n
from touchbench.benchmark.catalogue.tuning import check_budget, tuned_spec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import check_classifier
from touchbench.benchmark.problem import Problem, problem_from_dataset

#: A CLI flag (``--budget``) or command (``touchbench classifiers``).
CLI_WORDS = re.compile(r"(^|[\s`'\"(])--?[a-zA-Z]|touchbench [a-z]")

TWO_TARGETS = Problem(
    X=np.zeros((4, 1)),
    Y=np.array([[0, 1], [1, 0], [0, 0], [1, 1]]),
    n_classes=(2, 2),
    target_names=("gesture", "place"),
)

CASES: list[tuple[str, Callable[[], object], str]] = [
    (
        "unknown classifier",
        lambda: get_spec("qqqqqqqq"),
        "unknown classifier 'qqqqqqqq'; see the classifier listing",
    ),
    (
        "tuned twin without a space",
        lambda: tuned_spec(get_spec("nb")),
        "classifier 'nb' declares no search space, so it has no tuned twin (the classifier "
        "listing gives each entry's search space)",
    ),
    (
        "budget",
        lambda: check_budget(0),
        "`budget` must be more than 0 and at most 1440 minutes, got 0",
    ),
    ("stack range", lambda: check_top_n(0, 5), "`stack` must be between 1 and 20, got 0"),
    (
        "stack members",
        lambda: check_top_n(3, 2),
        "a stack of the top 3 needs at least 3 classifiers in the run to choose from, the run "
        "has 2",
    ),
    (
        "multi-class on two targets",
        lambda: check_classifier("nb", TWO_TARGETS),
        "'nb' is a multi-class classifier and the data set has 2 targets (gesture, place): "
        "choose one of them as `target`, or a multi-target configuration such as bcc:nb",
    ),
    (
        "targets of two kinds",
        lambda: problem_from_dataset(make([[0, 0, 2, 1.0, 0]], (0, 3))),
        "choose nominal ones to classify or numeric ones to regress (`target` or `targets`)",
    ),
    (
        "flat features for a sequence classifier",
        lambda: check_sequence_input(get_spec("minirocket"), None),
        "classifier 'minirocket' needs a sequence data set (attributes named CHANNEL[T], as the "
        "extractor `sequence`, or `mfcc` with its option frames=N, makes them); this data set "
        "has flat features",
    ),
]


@pytest.mark.parametrize(("what", "call", "expected"), CASES, ids=[c[0] for c in CASES])
def test_messages_name_fields_not_flags(
    what: str, call: Callable[[], object], expected: str
) -> None:
    with pytest.raises(ConfigurationError) as error:
        call()
    message = str(error.value)
    assert expected in message
    assert CLI_WORDS.search(message) is None, message


def test_the_cli_pattern_catches_flags_and_commands() -> None:
    for text in ("--budget must", "use `--target NAME`", "see `touchbench classifiers`", "-e mfcc"):
        assert CLI_WORDS.search(text), text
    assert CLI_WORDS.search("bcc:nb, x,y or x,y,z, CHANNEL[T], 2**62") is None
