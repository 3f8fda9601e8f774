"""Time touchbench's statistics across data sets and its CD diagram beside autorank and
baycomp, on the same random scores in one process.

- Demšar's procedure (ranks, Friedman, Nemenyi CD and p-values, Holm, groups) against
  autorank's Friedman-Nemenyi path (which also computes effect sizes and confidence
  intervals: it does more, so the ratio flatters us somewhat);
- the Bayesian signed-rank test against baycomp's (same number of posterior samples);
- the correlated t-test against baycomp's;
- a CD diagram rendered to SVG against autorank's ``plot_stats`` rendered to SVG.

Each is run several times; the table shows the best time of each and the ratio
(peer / touchbench).  The two sides' numbers are compared, and a disagreement is reported.
autorank and baycomp come with the ``test`` extra.

Usage::

    .venv/bin/python perf/statistics_speed.py [--datasets N] [--classifiers K] [--repeat R]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from touchbench.app.reports.plots import cd_diagram, svg_text
from touchbench.benchmark.evaluation.bayesian import correlated_ttest, signed_rank_test
from touchbench.benchmark.evaluation.score_table import ScoreTable
from touchbench.benchmark.evaluation.statistics import compare_classifiers


def best_time(call: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """The shortest of ``repeat`` timed calls, and the last result."""
    best, result = math.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = call()
        best = min(best, time.perf_counter() - start)
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--datasets", type=int, default=30)
    parser.add_argument("--classifiers", type=int, default=20)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    from autorank import autorank, plot_stats
    from baycomp import CorrelatedTTest, SignedRankTest
    from matplotlib import pyplot

    rng = np.random.default_rng(0)
    n, k = args.datasets, args.classifiers
    values = rng.normal(0.75, 0.05, size=(n, k)) + np.linspace(0.0, 0.08, k)
    names = [f"clf{j:02d}" for j in range(k)]
    frame = pd.DataFrame(values, columns=names)
    table = ScoreTable(values, tuple(f"d{i}" for i in range(n)), tuple(names))
    rows: list[tuple[str, float, float, str]] = []

    def quiet_autorank() -> Any:
        with contextlib.redirect_stdout(io.StringIO()):  # autorank prints its table
            return autorank(frame, alpha=0.05, order="descending", force_mode="nonparametric")

    ours_time, ours = best_time(lambda: compare_classifiers(table), args.repeat)
    peer_time, peer = best_time(quiet_autorank, args.repeat)
    agree = all(
        math.isclose(ours.average_rank(name), float(rank))
        for name, rank in peer.rankdf.meanrank.items()
    ) and math.isclose(ours.critical_difference, peer.cd, rel_tol=1e-4)
    rows.append((f"Friedman + Nemenyi, {n} x {k}", ours_time, peer_time, _agreement(agree)))

    a, b = values[:, -1], values[:, -2]
    ours_time, ours_sr = best_time(lambda: signed_rank_test(a, b, rope=0.01), args.repeat)
    peer_time, peer_sr = best_time(
        lambda: SignedRankTest.probs(a, b, rope=0.01, nsamples=50_000, random_state=0),
        args.repeat,
    )
    agree = np.allclose((ours_sr.p_left, ours_sr.p_rope, ours_sr.p_right), peer_sr, atol=0.015)
    rows.append((f"Bayesian signed-rank, {n} data sets", ours_time, peer_time, _agreement(agree)))

    x, y = rng.normal(0.8, 0.03, 100), rng.normal(0.79, 0.03, 100)
    ours_time, ours_ct = best_time(
        lambda: correlated_ttest(x, y, test_train_ratio=1 / 9, rope=0.01), args.repeat
    )
    peer_time, peer_ct = best_time(
        lambda: CorrelatedTTest.probs(x, y, rope=0.01, runs=10), args.repeat
    )
    agree = np.allclose((ours_ct.p_left, ours_ct.p_rope, ours_ct.p_right), peer_ct, atol=1e-12)
    rows.append(("correlated t-test, 10 x 10 folds", ours_time, peer_time, _agreement(agree)))

    def our_plot() -> int:
        figure = cd_diagram(
            dict(zip(ours.classifiers, ours.average_ranks.tolist(), strict=True)),
            ours.critical_difference,
            ours.groups,
            title="CD",
        )
        return len(svg_text(figure))

    def peer_plot() -> int:
        buffer = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()):
            plot_stats(peer)
        pyplot.savefig(buffer, format="svg")
        pyplot.close("all")
        return len(buffer.getvalue())

    ours_time, our_size = best_time(our_plot, args.repeat)
    peer_time, peer_size = best_time(peer_plot, args.repeat)
    rows.append(
        (
            f"CD diagram to SVG, {k} classifiers",
            ours_time,
            peer_time,
            f"{our_size / 1024:.0f} KiB vs {peer_size / 1024:.0f} KiB",
        )
    )

    print(f"{'task':<40} {'touchbench':>11} {'peer':>11} {'ratio':>7}  check")
    for task, ours_seconds, peer_seconds, check in rows:
        print(
            f"{task:<40} {ours_seconds * 1000:>9.1f}ms {peer_seconds * 1000:>9.1f}ms "
            f"{peer_seconds / ours_seconds:>6.1f}x  {check}"
        )
    print("peer: autorank (Friedman, Nemenyi, CD diagram), baycomp (Bayesian tests)")


def _agreement(agree: bool) -> str:
    return "same numbers" if agree else "DISAGREE"


if __name__ == "__main__":
    main()
