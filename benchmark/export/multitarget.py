"""A multi-target model as one ONNX graph: one sub-graph per base classifier, joined.

The input is the single-target graph's (``features``, see :mod:`benchmark.export.graph`).
Each target ``t`` has two outputs: ``label_<t>``, int64 of shape (n_instances,), the index
of the predicted label in the target's labels, and ``probabilities_<t>``, float32 of shape
(n_instances, n_labels[t]); the metadata key ``touchbench.targets`` lists the targets, their
labels and these names.

Exported meta-classifiers, each over a base that exports on its own:

- a target network (``cr``, ``cc``, ``bcc``): the links in the model's order, each fed the
  features followed by the one-hot codes of its parents' predicted labels (the most
  probable label, as :class:`benchmark.multitarget._network.TargetNetwork` feeds them);
- a label combination (``lc``, ``ps``, ``nsr``): one classifier over the combinations, the
  most probable combination's values as labels and each target's marginal as its
  probabilities (:class:`benchmark.multitarget.combination.LabelCombination`).

Other meta-classifiers (ensembles, partitions, probabilistic chains and the
scikit-multilearn adapters) are refused.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.export.convert import convert_pipeline
from touchbench.benchmark.export.graph import (
    INPUT,
    LABEL,
    PROBABILITIES,
    add_metadata,
    output_names,
)
from touchbench.benchmark.export.supported import refuse
from touchbench.benchmark.model import TrainedModel
from touchbench.benchmark.multitarget._target_classifier import TargetClassifier
from touchbench.benchmark.multitarget.bayesian_chain import BayesianClassifierChain
from touchbench.benchmark.multitarget.chains import ClassifierChain
from touchbench.benchmark.multitarget.combination import (
    LabelCombination,
    NearestSetReplacement,
    PrunedSets,
)
from touchbench.benchmark.multitarget.relevance import ClassRelevance
from touchbench.benchmark.problem import usable_feature_columns

#: Meta-classifiers whose models export, by registry id and class (exact classes: a
#: subclass that predicts otherwise, as the probabilistic chain, does not).
NETWORKS = {"cr": ClassRelevance, "cc": ClassifierChain, "bcc": BayesianClassifierChain}
COMBINATIONS = {"lc": LabelCombination, "ps": PrunedSets, "nsr": NearestSetReplacement}
EXPORTABLE_META = frozenset(NETWORKS) | frozenset(COMBINATIONS)


@dataclass
class _Graph:
    """Nodes, constants and opsets gathered from the sub-graphs and the joining nodes."""

    nodes: list[Any] = field(default_factory=list)
    initializers: list[Any] = field(default_factory=list)
    value_info: list[Any] = field(default_factory=list)
    opsets: dict[str, int] = field(default_factory=dict)
    ir_version: int = 0

    def node(self, op: str, inputs: list[str], outputs: list[str], **attributes: Any) -> None:
        from onnx import helper

        self.nodes.append(helper.make_node(op, inputs, outputs, **attributes))

    def constant(self, name: str, value: np.ndarray) -> str:
        from onnx import numpy_helper

        self.initializers.append(numpy_helper.from_array(value, name))
        return name

    def add(self, sub: Any, prefix: str) -> None:
        """Add a converted sub-graph, every name of it prefixed (its input becomes
        ``<prefix>features``, its outputs ``<prefix>label`` and ``<prefix>probabilities``)."""
        from onnx import compose

        sub = compose.add_prefix(sub, prefix)
        self.nodes.extend(sub.graph.node)
        self.initializers.extend(sub.graph.initializer)
        self.value_info.extend(sub.graph.value_info)
        for opset in sub.opset_import:
            self.opsets[opset.domain] = max(self.opsets.get(opset.domain, 0), opset.version)
        self.ir_version = max(self.ir_version, sub.ir_version)


def exports_multitarget(meta: str, base_exports: bool) -> bool:
    """Whether ``META:BASE`` models export (``base_exports``: whether the base does)."""
    return meta in EXPORTABLE_META and base_exports


def convert_multitarget(model: TrainedModel) -> Any:
    """The graph of a multi-target model (an ``onnx.ModelProto``), unchecked.

    Raises
    ------
    ConfigurationError
        A meta-classifier or base without a converter (one line naming what exports).
    """
    from onnx import TensorProto, helper

    estimator = model.estimator
    kind = type(estimator)
    n_inputs = len(usable_feature_columns(model.schema))
    graph = _Graph()
    if kind in NETWORKS.values():
        answers = _network(model, graph, n_inputs)
    elif kind in COMBINATIONS.values():
        answers = _combination(model, graph, n_inputs)
    else:
        refuse(model.classifier, kind.__name__)
    outputs = []
    for target, (label, probabilities) in zip(model.schema.targets, answers, strict=True):
        label_name, probabilities_name = output_names(target.name, several=True)
        graph.node("Identity", [label], [label_name])
        graph.node("Identity", [probabilities], [probabilities_name])
        outputs.append(helper.make_tensor_value_info(label_name, TensorProto.INT64, [None]))
        outputs.append(
            helper.make_tensor_value_info(
                probabilities_name, TensorProto.FLOAT, [None, len(target.values)]
            )
        )
    onnx_graph = helper.make_graph(
        graph.nodes,
        f"touchbench_{model.classifier}",
        [helper.make_tensor_value_info(INPUT, TensorProto.FLOAT, [None, n_inputs])],
        outputs,
        initializer=graph.initializers,
        value_info=graph.value_info,
    )
    onnx_model = helper.make_model(
        onnx_graph,
        opset_imports=[helper.make_opsetid(d, v) for d, v in sorted(graph.opsets.items())],
    )
    onnx_model.ir_version = graph.ir_version
    add_metadata(onnx_model, model)
    return onnx_model


def _link(
    model: TrainedModel, graph: _Graph, link: TargetClassifier, n_inputs: int, prefix: str
) -> tuple[str, str]:
    """Add one base classifier (its input ``<prefix>features``, filled by the caller);
    its label and its probabilities over every class, as :class:`TargetClassifier`."""
    if link.estimator_ is None:
        raise ConfigurationError(
            f"classifier '{model.classifier}': a base saw a single class in training; "
            "nothing to convert"
        )
    n_classes = int(link.classes_.shape[0])
    sub = convert_pipeline(
        model.classifier,
        link.estimator_,
        n_inputs=n_inputs,
        n_labels=n_classes,
        codes=np.asarray(link.present_classes_, dtype=np.int64),
    )
    graph.add(sub, prefix)
    label, probabilities = f"{prefix}{LABEL}", f"{prefix}{PROBABILITIES}"
    if link.probabilistic_:
        # TargetClassifier.predict: the most probable class, the first of equals
        argmax = f"{prefix}argmax"
        graph.node("ArgMax", [probabilities], [argmax], axis=1, keepdims=0)
        return argmax, probabilities
    # no probabilities: the one-hot code of the label, as TargetClassifier gives
    one_hot = f"{prefix}one_hot"
    identity = graph.constant(f"{prefix}identity", np.eye(n_classes, dtype=np.float32))
    graph.node("Gather", [identity, label], [one_hot])
    return label, one_hot


def _network(model: TrainedModel, graph: _Graph, n_inputs: int) -> list[tuple[str, str]]:
    """The links of a target network in its order; each target's label and probabilities."""
    network = model.estimator
    n_classes = network.n_classes_
    answers: dict[int, tuple[str, str]] = {}
    one_hot: dict[int, str] = {}
    for target in (int(t) for t in network.order_):
        parents = network.parents_[target]
        prefix = f"touchbench_t{target}_"
        design = f"{prefix}{INPUT}"
        # the features, then the one-hot codes of the parents' labels (TargetNetwork._design)
        graph.node("Concat", [INPUT] + [one_hot[p] for p in parents], [design], axis=1)
        width = n_inputs + sum(n_classes[p] for p in parents)
        answers[target] = _link(model, graph, network.estimators_[target], width, prefix)
        identity = graph.constant(f"{prefix}codes", np.eye(n_classes[target], dtype=np.float32))
        one_hot[target] = f"{prefix}label_one_hot"
        graph.node("Gather", [identity, answers[target][0]], [one_hot[target]])
    return [answers[t] for t in range(len(n_classes))]


def _combination(model: TrainedModel, graph: _Graph, n_inputs: int) -> list[tuple[str, str]]:
    """The classifier over combinations; each target's value in the most probable
    combination, and its marginal over the combinations' probabilities."""
    combination = model.estimator
    combinations = np.asarray(combination.combinations_, dtype=np.int64)
    prefix = "touchbench_lc_"
    graph.node("Identity", [INPUT], [f"{prefix}{INPUT}"])
    chosen, probabilities = _link(model, graph, combination.estimator_, n_inputs, prefix)
    answers = []
    for target, k in enumerate(combination.n_classes_):
        values = graph.constant(f"touchbench_values_{target}", combinations[:, target].copy())
        label = f"touchbench_label_of_{target}"
        graph.node("Gather", [values, chosen], [label])
        marginal = np.zeros((combinations.shape[0], k), dtype=np.float32)
        marginal[np.arange(combinations.shape[0]), combinations[:, target]] = 1.0
        columns = graph.constant(f"touchbench_marginal_{target}", marginal)
        summed = f"touchbench_probabilities_of_{target}"
        graph.node("MatMul", [probabilities, columns], [summed])
        answers.append((label, summed))
    return answers
