"""Results in WEKA's InstanceResultListener format: attributes, values, readable back."""

from __future__ import annotations

import math
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest

from touchbench.benchmark.catalogue import CATALOGUE, parse_weka_command
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.results_arff import (
    RESULT_ATTRIBUTES,
    results_to_dataset,
    weka_measures,
)
from touchbench.benchmark.io.arff import dumps_arff, loads_arff, read_arff
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.run.task import TaskContext, TaskKey, TaskResult, execute_task


@pytest.fixture(scope="module")
def results() -> list[TaskResult]:
    rng = np.random.default_rng(0)
    y = np.arange(60) % 3
    problem = Problem(
        X=rng.normal(size=(60, 3)) + y[:, None], Y=y[:, None], n_classes=(3,), target_names=("g",)
    )
    folds, _ = make_folds(problem.Y, n_folds=3, n_repeats=2)
    context = TaskContext(problem, CATALOGUE, folds)
    keys = [TaskKey(c, f.repeat, f.fold) for c in ("ibk", "ibk3", "nb") for f in folds]
    out = [execute_task(context, key) for key in keys]
    out.append(TaskResult(TaskKey("j48", 0, 0), "error", "ValueError: boom", {}, None, 40, 20))
    return out


def test_export_reads_back_with_weka_attribute_names_and_one_row_per_success(
    results: list[TaskResult],
) -> None:
    moment = datetime(2017, 9, 22, 9, 48)
    dataset = results_to_dataset(
        results, dataset_name="Sound_Gestures: -C 1", specs=CATALOGUE, timestamp=moment
    )
    text = dumps_arff(dataset)
    assert text.startswith("@relation InstanceResultListener")
    back = loads_arff(text)
    names = [a.name for a in back.schema.attributes]
    assert names[:6] == [
        "Key_Dataset",
        "Key_Run",
        "Key_Fold",
        "Key_Scheme",
        "Key_Scheme_options",
        "Key_Scheme_version_ID",
    ]
    assert names[6:-1] == list(RESULT_ATTRIBUTES) and names[-1] == "Summary"
    assert back.n_instances == 18  # 3 classifiers x 2 runs x 3 folds; the error is left out
    column = {name: back.values[:, i] for i, name in enumerate(names)}
    labels = {a.name: a.values for a in back.schema.attributes}
    assert labels["Key_Run"] == ("1", "2") and labels["Key_Fold"] == ("1", "2", "3")
    assert labels["Key_Scheme"] == (
        "weka.classifiers.lazy.IBk",
        "weka.classifiers.bayes.NaiveBayes",
    )
    # WEKA-named entries are written as WEKA writes their command: class, then options
    assert labels["Key_Scheme_options"] == (
        CATALOGUE["ibk"].weka_options,
        CATALOGUE["ibk3"].weka_options,
        "",
    )
    assert labels["Key_Scheme_options"][0].startswith("-K 1 -W 0 -A ")
    for scheme, options in zip(labels["Key_Scheme"], labels["Key_Scheme_options"][1:], strict=True):
        assert parse_weka_command(f"{scheme} {options}").id in ("ibk3", "nb")
    np.testing.assert_array_equal(column["Date_time"], 20170922.0948)
    np.testing.assert_array_equal(column["Number_of_testing_instances"], 20)
    nb = [r for r in results if r.key.classifier == "nb"]
    nb_rows = column["Key_Scheme_options"] == 2
    assert column["Percent_correct"][nb_rows].mean() == pytest.approx(
        100 * np.mean([r.metrics["accuracy"] for r in nb])
    )
    assert column["Weighted_avg_F_measure"][nb_rows].mean() == pytest.approx(
        np.mean([r.metrics["f1_weighted"] for r in nb])
    )
    assert np.isnan(column["SF_prior_entropy"]).all() and np.isnan(column["Summary"]).all()


def test_scheme_names_can_be_touchbench_ids(results: list[TaskResult]) -> None:
    dataset = results_to_dataset(results, dataset_name="d", specs=CATALOGUE, scheme_names="id")
    scheme = dataset.schema.attributes[dataset.schema.index("Key_Scheme")]
    assert scheme.values == ("touchbench.ibk", "touchbench.ibk3", "touchbench.nb")
    options = dataset.schema.attributes[dataset.schema.index("Key_Scheme_options")]
    assert options.values == (
        "-id ibk -n_neighbors 1",
        "-id ibk3 -n_neighbors 3",
        "-id nb -numeric normal",
    )


def test_entries_without_a_weka_command_keep_their_touchbench_name() -> None:
    result = TaskResult(TaskKey("rf", 0, 0), "ok", None, {}, [[3, 1], [1, 5]], 90, 10)
    dataset = results_to_dataset([result], dataset_name="d", specs=CATALOGUE)
    keys = {a.name: a.values for a in dataset.schema.attributes[:6]}
    assert keys["Key_Scheme"] == ("touchbench.rf",)
    assert keys["Key_Scheme_options"] == ("-id rf -n_estimators 100",)


def test_weka_measures_by_hand() -> None:
    result = TaskResult(
        TaskKey("x", 0, 0),
        "ok",
        None,
        {"kappa": 0.5, "fit_time": 1.5, "fit_cpu_time": 0.25, "model_size": 1000.0},
        [[3, 1, 0], [1, 2, 1], [0, 0, 2]],
        90,
        10,
    )
    m = weka_measures(result)
    assert (m["Number_correct"], m["Number_incorrect"], m["Percent_correct"]) == (7, 3, 70)
    # first class: TP 3, FN 1, FP 1, TN 5
    assert (m["Num_true_positives"], m["Num_false_negatives"]) == (3, 1)
    assert (m["Num_false_positives"], m["Num_true_negatives"]) == (1, 5)
    assert m["True_positive_rate"] == pytest.approx(0.75)
    assert m["False_positive_rate"] == pytest.approx(1 / 6)
    assert m["True_negative_rate"] == pytest.approx(5 / 6)
    assert m["IR_precision"] == pytest.approx(0.75) and m["F_measure"] == pytest.approx(0.75)
    assert m["Matthews_correlation"] == pytest.approx((15 - 1) / math.sqrt(4 * 4 * 6 * 6))
    # false positive rates 1/6, 1/6, 1/8 weighted by supports 4, 4, 2
    assert m["Weighted_avg_false_positive_rate"] == pytest.approx(0.4 / 6 + 0.4 / 6 + 0.2 / 8)
    f = np.array([0.75, 2 * (2 / 3) * 0.5 / (2 / 3 + 0.5), 2 * (2 / 3) / (2 / 3 + 1)])
    assert m["Weighted_avg_F_measure"] == pytest.approx(np.array([0.4, 0.4, 0.2]) @ f)
    assert m["Unweighted_macro_avg_F_measure"] == pytest.approx(f.mean())
    assert m["Unweighted_micro_avg_F_measure"] == pytest.approx(0.7)
    assert m["Kappa_statistic"] == 0.5 and m["Elapsed_Time_training"] == 1.5
    assert m["UserCPU_Time_millis_training"] == 250 and m["Serialized_Model_Size"] == 1000
    assert math.isnan(m["Elapsed_Time_testing"])


def test_multitarget_results_are_refused() -> None:
    result = TaskResult(TaskKey("cc:nb", 0, 0), "ok", None, {}, [[[1, 0], [0, 1]]], 9, 1)
    with pytest.raises(ConfigurationError, match="multi-class runs only"):
        results_to_dataset([result], dataset_name="d", specs=CATALOGUE)


@pytest.mark.shared
def test_attributes_match_wekas_own_results_file(
    shared_datasets: Path, results: list[TaskResult]
) -> None:
    weka = read_arff(shared_datasets / "uc3m-touch/mini/weka_results_gesture.arff")
    ours = results_to_dataset(results, dataset_name="d", specs=CATALOGUE)
    theirs = [(a.name, a.kind) for a in weka.schema.attributes]
    mine = [(a.name, a.kind) for a in ours.schema.attributes]
    assert mine == theirs[: len(mine)]
    assert theirs[len(mine)][0].startswith("measure")
