"""A race's schedule replayed on a full run's measured task seconds: where its time goes.

``perf/racing.py --save FILE`` pickles each full run it makes (results and entry ids); this
script replays the raced run's schedule (:class:`benchmark.run.schedule.RoundSchedule`, the
same decisions) on a simulated clock with ``--workers`` workers, each task taking the CPU
seconds (fit and predict) it took in the full run.  The CPU seconds barely move with the
machine's load, unlike wall seconds, so schedules can be compared on a busy machine.
Printed: the replayed wall seconds and their ratio to the full run's (replayed alike),
tasks started and handed on (a task started for an entry the race then drops is wasted),
worker seconds idle, the drops per fold, the full top 5 still live, the winner's
difference, and the floor of any race that keeps the full top 5 to the end.  ``--against
COMMIT`` replays that commit's schedule and race rule beside it.

    .venv/bin/python perf/racing.py --robots maggie --tasks gesture --save maggie.pkl
    .venv/bin/python perf/racing_replay.py maggie.pkl [--workers 2,4] [--against 1d4384d]
        [--first-round 2] [--alpha 0.01]
"""

from __future__ import annotations

import argparse
import heapq
import importlib.util
import pickle
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.results import Drop, TaskKey, TaskResult
from touchbench.benchmark.run.racing import FIRST_ROUND, RaceRule
from touchbench.benchmark.run.schedule import RoundSchedule

#: Seconds of a task beyond its fit and predict (the worker's own work and the result's way
#: back), as measured: a raced run on Mini gesture spent 129.3 s between its 230 tasks'
#: starts and results, 128.5 s of them fitting and predicting.
OVERHEAD = 0.004


def seconds(result: TaskResult) -> float:
    """CPU seconds of a task (fit and predict) and the worker's own overhead."""
    m = result.metrics
    return m.get("fit_cpu_time", 0.0) + m.get("predict_cpu_time", 0.0) + OVERHEAD


def replay(
    saved: dict[str, Any],
    schedule: type,
    workers: int,
    metric: str,
    alpha: float,
    first_round: int = FIRST_ROUND,
) -> dict[str, Any]:
    """The race of ``schedule`` on the saved run's task seconds, ``workers`` at a time."""
    results = {r.key: r for r in saved["results"]}
    derived, helpers = derived_of(saved)
    entries = [*saved["ids"], *(h for h in helpers if h not in saved["ids"])]
    rounds = sorted({(k.repeat, k.fold) for k in results})
    clock = [0.0]
    delivered: list[TaskResult] = []
    drops: list[Drop] = []
    # hints: each entry's mean (what the schedule learns after its first timed fold)
    hints = {e: float(np.mean([seconds(r) for k, r in results.items() if k.classifier == e]))
             for e in entries if e not in derived}  # fmt: skip
    options = {"derived": derived, "helpers": helpers} if derived else {}
    source = schedule(
        entries,
        rounds,
        delivered.append,
        hints=hints,
        race=RaceRule(metric, alpha, first_round=first_round),
        test_train_ratio=float(np.mean([r.n_test / max(r.n_train, 1) for r in results.values()])),
        on_drop=drops.append,
        clock=lambda: clock[0],
        **options,
    )
    arrived: set[TaskKey] = set()
    running: list[tuple[float, int, TaskKey]] = []
    free, started, idle = workers, 0, 0.0
    while True:
        while free and not source.exhausted and (key := source.next_task()) is not None:
            heapq.heappush(running, (clock[0] + seconds(results[key]), started, key))
            started, free = started + 1, free - 1
        if not running:
            break
        end, _, key = heapq.heappop(running)
        idle += free * (end - clock[0])
        clock[0], free = end, free + 1
        source.arrived(results[key])
        arrived.add(key)
        for entry, members in derived.items():  # computed as soon as its members are in
            fold = TaskKey(entry, key.repeat, key.fold)
            ready = all(TaskKey(m, key.repeat, key.fold) in arrived for m in members)
            if fold not in arrived and ready:
                arrived.add(fold)
                source.arrived(results[fold])
    source.finish()
    return {"wall": clock[0], "started": started, "delivered": delivered, "drops": drops,
            "idle": idle}  # fmt: skip


def derived_of(saved: dict[str, Any]) -> tuple[dict[str, list[str]], list[str]]:
    """The saved run's entries computed from others' folds (with every entry they use) and
    its helpers; a file saved before ensembles came from fold predictions has none."""
    return saved.get("derived", {}), saved.get("helpers", [])


def _module_of(commit: str, path: str, name: str) -> Any:
    """The module at ``path`` as it was at ``commit``, loaded under ``name``."""
    text = subprocess.run(
        ["git", "show", f"{commit}:{path}"],
        capture_output=True,
        text=True,
        check=True,
        cwd=Path(__file__).resolve().parents[1],
    ).stdout
    file = Path(tempfile.mkdtemp()) / f"{name}.py"
    file.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(name, file)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def schedule_of(commit: str) -> type:
    """``RoundSchedule`` as ``benchmark/run/schedule.py`` was at ``commit``, deciding by
    ``benchmark/run/racing.py``'s rule of then."""
    schedule = _module_of(commit, "benchmark/run/schedule.py", "schedule_then")
    racing = _module_of(commit, "benchmark/run/racing.py", "racing_then")
    schedule.race_round = racing.race_round
    return schedule.RoundSchedule


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("saved", nargs="+", help="files perf/racing.py --save wrote")
    parser.add_argument("--workers", default="2")
    parser.add_argument("--alpha", type=float, default=0.01)
    parser.add_argument("--metric", default="f1_weighted")
    parser.add_argument(
        "--first-round", type=int, default=FIRST_ROUND, help="folds before the first decision"
    )
    parser.add_argument("--against", metavar="COMMIT", default=None)
    args = parser.parse_args()
    schedules: list[tuple[str, type]] = [("now", RoundSchedule)]
    if args.against:
        schedules.insert(0, (args.against, schedule_of(args.against)))
    for name in args.saved:
        with open(name, "rb") as file:
            saved = pickle.load(file)  # our own file, written by perf/racing.py
        metric = args.metric
        full_board = build_leaderboard(saved["results"], metric=metric)
        top = [row.classifier for row in full_board.rows[:5]]
        not_worse = [row.classifier for row in full_board.rows if row.mark != "*"]
        derived, _ = derived_of(saved)
        cost = {r.key: seconds(r) for r in saved["results"] if r.key.classifier not in derived}
        total = sum(cost.values())
        # what the top 5 fit: themselves, or the members they are computed from
        fitted = set(top).union(*(derived.get(entry, ()) for entry in top))
        floor = sum(
            v for k, v in cost.items() if k.classifier in fitted or k.fold < args.first_round
        )
        print(f"\n{name}: {len(saved['ids'])} entries, {len(cost)} tasks, {total:.0f} CPU s")
        print(f"  full top 5: {', '.join(top)}; their share of the seconds "
              f"{sum(v for k, v in cost.items() if k.classifier in fitted) / total:.3f}; floor of "
              f"a race keeping them: {floor / total:.3f}")  # fmt: skip
        for workers in (int(w) for w in args.workers.split(",")):
            full_wall = total / workers
            for label, schedule in schedules:
                first = args.first_round if label == "now" else FIRST_ROUND
                out = replay(saved, schedule, workers, metric, args.alpha, first)
                dropped = {d.classifier: d for d in out["drops"]}
                board = build_leaderboard(out["delivered"], metric=metric, drops=dropped)
                best = next(row for row in board.rows if row.dropped is None)
                difference = abs(full_board.rows[0].metrics[metric][0] - best.metrics[metric][0])
                when = dict(sorted(Counter(d.after_fold for d in out["drops"]).items()))
                print(
                    f"  {workers} workers, schedule {label}: ratio "
                    f"{out['wall'] / full_wall:.3f} ({out['wall']:.0f} / {full_wall:.0f} s), "
                    f"{out['started']} started, {len(out['delivered'])} handed on, idle "
                    f"{out['idle'] / (workers * out['wall']):.3f}, {len(dropped)} dropped "
                    f"(after fold: {when}), top 5 live "
                    f"{sum(e not in dropped for e in top)}/5, winner difference {difference:.4f}"
                )
                lost = [e for e in not_worse if e in dropped]
                print(
                    f"    not marked worse than the full run's winner: "
                    f"{len(not_worse) - len(lost)}/{len(not_worse)} live"
                    + "".join(
                        f"; {e} dropped after fold {dropped[e].after_fold} "
                        f"(p {dropped[e].p_value:.4f} against {dropped[e].leader})"
                        for e in lost
                    )
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
