"""What a fitted model chose on its training fold: a tuned twin's parameters, a stack's
members, or, inside a multi-target meta-classifier, what each per-target search chose.

The multi-target meta-classifiers are walked by their fitted attributes, not their classes:
``estimators_`` with ``order_`` is one model per target (CR, CC, BCC, PCC), ``estimators_``
with ``partition_`` one per subset of targets (RAkELd, SCC), any other ``estimators_`` list
an ensemble's members (ECC, EPS), ``estimator_`` a single wrapped model (LC, PS, NSR, and
the per-target wrapper).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

from touchbench.benchmark.catalogue.spec import jsonable

#: Key of the whole model's choice in a multi-target record: a model over the joint target
#: combinations (LC, PS, NSR) searches once for every target.
JOINT = "joint"


def chosen_params(
    model: object, target_names: Sequence[str] | None = None
) -> dict[str, Any] | None:
    """What a tuned twin, a stack or every search inside a multi-target model chose.

    Parameters
    ----------
    model : estimator
        A fitted model: a catalogue pipeline, or a multi-target meta-classifier over one.
    target_names : sequence of str, optional
        Names of the targets, in column order: given for a multi-target model only, whose
        inner searches are then looked for.

    Returns
    -------
    dict or None
        A single-target model: its final step's ``best_params_`` (values JSON cannot hold
        as their ``repr``). A multi-target model: where each search sits (a target's name,
        ``"gesture+position"`` for a subset of targets, ``"joint"`` for one model over
        the target combinations, ``"member 2/gesture"`` inside an ensemble) -> its
        ``best_params_``; a target that was constant in the training fold has no search
        and no key. ``None`` when nothing chose anything.
    """
    own = _best_params(model)
    if own is not None or target_names is None:
        return own
    found = {path or JOINT: params for path, params in _walk(model, "", list(target_names))}
    return found or None


def _best_params(model: object) -> dict[str, Any] | None:
    steps = getattr(model, "steps", None)
    final = steps[-1][1] if steps else model
    chosen = getattr(final, "best_params_", None)
    if not isinstance(chosen, dict):
        return None
    return {str(name): jsonable(value) for name, value in chosen.items()}


def _walk(model: object, path: str, names: list[str]) -> Iterator[tuple[str, dict[str, Any]]]:
    """(path, chosen parameters) of every search inside a fitted multi-target model."""
    own = _best_params(model)
    if own is not None:
        yield path, own
        return
    members = getattr(model, "estimators_", None)
    if isinstance(members, list):
        partition = getattr(model, "partition_", None)
        for i, member in enumerate(members):
            if hasattr(model, "order_"):
                label = names[i] if i < len(names) else f"target {i + 1}"
            elif partition is not None and i < len(partition):
                label = "+".join(_name(int(t), names) for t in partition[i])
            else:
                label = f"member {i + 1}"
            yield from _walk(member, f"{path}/{label}" if path else label, names)
        return
    inner = getattr(model, "estimator_", None)
    if inner is not None:
        yield from _walk(inner, path, names)


def _name(target: int, names: list[str]) -> str:
    return names[target] if target < len(names) else f"target {target + 1}"
