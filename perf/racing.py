"""Racing against the full run, side by side: the same top of the leaderboard in less time?

For each robot (Mini, Maggie) and task (``gesture`` multi-class, ``gesture+place``
multi-target), the suite runs under k-fold cross-validation twice with the same seed: in
full, and raced (``--race``, alpha 0.01).  Printed per data set:

- wall seconds of each and their ratio raced / full (issue 35's goals are against an older
  full run: ``--against`` below);
- the full run's top 5 and the entries it does not mark significantly worse than its
  winner: how many are still live at the end of the race, and the raced winner's score
  beside the full winner's;
- with ``--budget-fraction F`` a third run with a total budget of F x the full run's wall
  time: what it completed and cut, and its wall time against the budget;
- on the full run's per-fold scores, the two racing rules the issue weighs, replayed round
  by round: the corrected resampled t-test against the leader (what ``--race`` does) and
  Friedman's test with Nemenyi's critical difference of mean ranks (F-race's post-hoc):
  entries each drops, tasks saved, and whether the full top 5 survive.

    .venv/bin/python perf/racing.py [--robots mini,maggie] [--tasks gesture,gesture+place]
        [--suite default] [--folds 10] [--jobs 2] [--budget-fraction 0.333]

The data are ``../shared/datasets/uc3m-touch`` (see its README); without them the script
says so and stops.

Side by side with older code (issue 35: ensembles from fold predictions), ``--against
WORKTREE`` runs, per data set and alternating, the older code's full run, then this code's
full run, ``--race`` and ``--ensemble N``, each in a process of its own (the older code
imported from WORKTREE, as ``benchmark`` before the one package, else ``touchbench``), and
prints one Markdown row per data set for ``docs/racing.md``: wall ratios against the older
full run, winners, how far the redefined ensembles' scores moved, whether the race kept every
entry the full run does not mark significantly worse than its winner, and the selection's
score against the best single entry and its cost against this code's full run::

    git -C /work/main worktree add /work/wt/beb0232 beb0232
    .venv/bin/python perf/racing.py --against /work/wt/beb0232 --tasks gesture \
        [--rounds 2] [--ensemble 5] [--quick] [--race-only]

Each pass's race is also printed against the older run of the same pass (the machine's speed
drifts less within a pass than across passes). ``--race-only`` runs only those two, for more
passes of the ratio at the goal's edge.

``--quick`` (a busy machine: the script works, the figures are not final): the fast suite
with ``voting`` and ``voting-hard``, 3 folds, 600 instances of each data set.
"""

from __future__ import annotations

import argparse
import math
import os
import pickle
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import rankdata, studentized_range

from touchbench.benchmark.evaluation.leaderboard import build_leaderboard, scores_by_fold
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.results import Drop, TaskResult
from touchbench.benchmark.run.engine import Problem, RaceRule, run_tasks
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.run.members import plan_run
from touchbench.benchmark.run.racing import FIRST_ROUND, decide

#: ``../shared/datasets`` beside the project; ``TOUCHBENCH_DATASETS`` names another place
#: (a git worktree of the project sits elsewhere).
DATASETS = (
    Path(
        os.environ.get(
            "TOUCHBENCH_DATASETS", Path(__file__).resolve().parents[2] / "shared/datasets"
        )
    )
    / "uc3m-touch"
)
TIMEOUT = 600.0


def load(robot: str, task: str) -> Problem:
    """``gesture`` alone (multi-class) or ``gesture+place`` (multi-target) of a robot."""
    data = read_arff(DATASETS / robot / "gesture_and_place.arff")
    names = list(data.schema.target_names)
    wanted = task.split("+")
    targets = [data.schema.target_indices[names.index(name)] for name in wanted]
    features = [i for i in range(data.schema.n_attributes) if i not in data.schema.target_indices]
    return Problem(
        X=data.values[:, features],
        Y=data.values[:, targets].astype(np.int64),
        n_classes=tuple(len(data.schema.targets[names.index(n)].values) for n in wanted),
        target_names=tuple(wanted),
    )


def regression(n: int) -> Problem:
    """``perf/regression_catalogue.py``'s contact-localisation data: (x, y) of ``n`` touches."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from regression_catalogue import contact_problem

    return contact_problem(n, 30, 0)


def suite_ids(problem: Problem, name: str) -> list[str]:
    if problem.kind == "regression":
        from touchbench.benchmark.catalogue.regressors import regression_suite

        return regression_suite(
            name, n_targets=problem.n_targets, n_instances=int(problem.X.shape[0])
        )
    if problem.n_targets > 1:
        from touchbench.benchmark.multitarget.suites import multitarget_suite

        return multitarget_suite(name)
    from touchbench.benchmark.catalogue import suite
    from touchbench.benchmark.estimators import reads_sequences

    return [i for i in suite(name) if not reads_sequences(i)]


#: ``--dask``: the address of the local Dask cluster the runs go to.
SCHEDULER: list[str] = []


def timed(problem: Problem, ids: list[str], folds: list, jobs: int, **options: Any):
    drops: list[Drop] = []
    start = time.perf_counter()
    results = run_tasks(
        problem,
        ids,
        folds,
        jobs=jobs,
        timeout=TIMEOUT,
        on_drop=drops.append,
        scheduler=SCHEDULER[0] if SCHEDULER else None,
        **options,
    )
    return results, {d.classifier: d for d in drops}, time.perf_counter() - start


def per_fold(results: list[TaskResult], metric: str) -> dict[str, dict[int, float]]:
    """Entry -> round -> score (rounds in fold order)."""
    by_entry: dict[str, list[TaskResult]] = {}
    for result in results:
        by_entry.setdefault(result.key.classifier, []).append(result)
    return {
        entry: {fold: score for (_, fold), score in scores_by_fold(rs, metric).items()}
        for entry, rs in by_entry.items()
    }


def full_top(results: list[TaskResult], metric: str, n: int = 5) -> set[str]:
    """The first ``n`` entries of the full run's leaderboard."""
    return {row.classifier for row in build_leaderboard(results, metric=metric).rows[:n]}


def replay_ttest(scores, metric: str, alpha: float, ratio: float, n_rounds: int):
    """Entries the t-test race drops on these scores, with the round of each drop."""
    live, dropped = list(scores), {}
    rule = RaceRule(metric, alpha)
    for index in range(n_rounds):
        upto = {e: {r: s for r, s in scores[e].items() if r <= index} for e in live}
        for drop in decide(rule, upto, live, index, test_train_ratio=ratio):
            dropped[drop.classifier] = index + 1
            live.remove(drop.classifier)
    return dropped


def nemenyi_cd(k: int, n: int, alpha: float) -> float:
    """Nemenyi's critical difference of mean ranks for k entries on n blocks."""
    q = studentized_range.ppf(1 - alpha, k, 1e6) / math.sqrt(2)
    return float(q * math.sqrt(k * (k + 1) / (6.0 * n)))


def replay_nemenyi(scores, lower: bool, alpha: float, n_rounds: int):
    """Entries F-race's post-hoc drops: mean rank (over the rounds so far, among the live
    entries) more than Nemenyi's critical difference behind the best."""
    live, dropped = [e for e in scores if len(scores[e]) == n_rounds], {}
    for index in range(FIRST_ROUND - 1, n_rounds):
        table = np.array([[scores[e][r] for r in range(index + 1)] for e in live])
        ranks = np.apply_along_axis(rankdata, 0, table if lower else -table)
        mean_ranks = ranks.mean(axis=1)
        cd = nemenyi_cd(len(live), index + 1, alpha)
        best = mean_ranks.min()
        for entry, rank in zip(list(live), mean_ranks, strict=True):
            if rank - best > cd:
                dropped[entry] = index + 1
                live.remove(entry)
    return dropped


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="mini,maggie")
    parser.add_argument("--tasks", default="gesture,gesture+place")
    parser.add_argument("--suite", default="default")
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--alpha", type=float, default=0.01)
    parser.add_argument("--budget-fraction", type=float, default=None)
    parser.add_argument(
        "--regression",
        type=int,
        default=0,
        metavar="N",
        help="race the regression suite on perf/regression_catalogue.py's data of N touches "
        "instead of the robots",
    )
    parser.add_argument(
        "--dask", action="store_true", help="on a local Dask cluster of --jobs workers"
    )
    parser.add_argument(
        "--against",
        metavar="WORKTREE",
        default=None,
        help="side by side with the code of this worktree (issue 35's measurement)",
    )
    parser.add_argument(
        "--ensemble", type=int, default=5, help="with --against: N (0: no selection run)"
    )
    parser.add_argument("--rounds", type=int, default=1, help="with --against: passes")
    parser.add_argument(
        "--race-only",
        action="store_true",
        help="with --against: the older full run and this code's race alone, alternating "
        "(more passes of the ratio at the goal's edge)",
    )
    parser.add_argument("--quick", action="store_true", help="with --against: a quick check")
    parser.add_argument("--keep", metavar="FILE", help="with --against: append each run's JSON")
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    parser.add_argument(
        "--save",
        metavar="FILE",
        default=None,
        help="pickle the (last) full run for perf/racing_replay.py",
    )
    parser.add_argument(
        "--full-only", action="store_true", help="the full run alone (with --save: for replays)"
    )
    args = parser.parse_args()
    if not args.regression and not DATASETS.is_dir():
        print(f"skipped: {DATASETS} is absent (the shared reference data sets)")
        return 0
    if args.child:
        return child(args)
    if args.against:
        return side_by_side(args)
    if args.dask:
        from distributed import LocalCluster

        cluster = LocalCluster(
            n_workers=args.jobs, threads_per_worker=1, processes=True, dashboard_address=None
        )
        SCHEDULER.append(cluster.scheduler_address)
    pairs = (
        [("contact", "x+y")]
        if args.regression
        else [(r, t) for r in args.robots.split(",") for t in args.tasks.split(",")]
    )
    for robot, task in pairs:
        problem = regression(args.regression) if args.regression else load(robot, task)
        ids = suite_ids(problem, args.suite)
        metric = (
            "mae"
            if problem.kind == "regression"
            else "hamming_score"
            if problem.n_targets > 1
            else "f1_weighted"
        )
        folds = make_folds(
            problem.Y,
            n_folds=args.folds,
            seed=args.seed,
            target_names=problem.target_names,
            regression=problem.kind == "regression",
        )[0]
        ratio = float(np.mean([f.test.size / f.train.size for f in folds]))
        print(f"\n{robot} {task}: {len(ids)} entries ({args.suite}), {len(folds)} folds")
        plan = plan_run(problem, ids)
        # an ensemble of entries has no seconds of its own: its results carry its members'
        derived = {entry: sorted(plan.uses(entry)) for entry in plan.derived}
        full, _, full_wall = timed(problem, ids, folds, args.jobs, random_state=args.seed)
        if args.save:
            with open(args.save, "wb") as file:
                pickle.dump(
                    {"ids": ids, "results": full, "wall": full_wall, "derived": derived,
                     "helpers": list(plan.helpers)},
                    file,
                )  # fmt: skip
        if args.full_only:
            print(f"  full : {full_wall:7.1f} s, {len(full)} tasks")
            continue
        race = RaceRule(metric, args.alpha)
        raced, drops, raced_wall = timed(
            problem, ids, folds, args.jobs, random_state=args.seed, race=race
        )
        full_board = build_leaderboard(full, metric=metric)
        raced_board = build_leaderboard(raced, metric=metric, drops=drops)
        top = [row.classifier for row in full_board.rows[:5]]
        top_live = [entry for entry in top if entry not in drops]
        full_best = full_board.rows[0]
        raced_best = next(row for row in raced_board.rows if row.dropped is None)
        difference = abs(full_best.metrics[metric][0] - raced_best.metrics[metric][0])
        print(f"  full : {full_wall:7.1f} s, {len(full)} tasks")
        when = dict(sorted(Counter(d.after_fold for d in drops.values()).items()))
        print(
            f"  raced: {raced_wall:7.1f} s, {len(raced)} tasks, {len(drops)} dropped "
            f"(after fold: {when})"
        )
        print(f"  wall ratio raced/full: {raced_wall / full_wall:.3f}")
        # the floor of that ratio: the share of the full run's fit and predict seconds
        # spent on what the race still runs
        seconds = {r.key: r.metrics.get("fit_time", 0.0) + r.metrics.get("predict_time", 0.0)
                   for r in full if r.ok and r.key.classifier not in derived}  # fmt: skip
        kept = {r.key for r in raced}
        share = sum(v for k, v in seconds.items() if k in kept) / max(sum(seconds.values()), 1e-9)
        print(f"  share of the full run's fit+predict seconds the race still spends: {share:.3f}")
        # where the raced run's time went: its workers' seconds not spent fitting or
        # predicting (start-up, waiting for a decision, the pool's own work)
        busy = sum(
            r.metrics.get("fit_time", 0.0) + r.metrics.get("predict_time", 0.0)
            for r in raced
            if r.ok and r.key.classifier not in derived
        )
        print(
            f"  raced run's worker seconds not in fit+predict: "
            f"{1 - busy / (args.jobs * raced_wall):.3f} of {args.jobs} x {raced_wall:.0f} s"
        )
        spent: Counter[str] = Counter()
        for r in raced:
            if r.key.classifier in derived:
                continue
            spent[r.key.classifier] += r.metrics.get("fit_time", 0.0) + r.metrics.get(
                "predict_time", 0.0
            )
        print(
            f"  {len(ids) - len(drops)} live at the end; dearest in the race: "
            + ", ".join(f"{e} {v / max(busy, 1e-9):.0%}" for e, v in spent.most_common(5))
        )
        # the floor of any race that keeps the full top 5 to the end: every entry's
        # first folds before the first decision, and every fold of the top 5
        first = {(0, f) for f in range(FIRST_ROUND)}
        floor = sum(
            v
            for k, v in seconds.items()
            if k.classifier in full_top(full, metric) or (k.repeat, k.fold) in first
        ) / max(sum(seconds.values()), 1e-9)
        print(
            f"  floor of a race keeping the full top 5 (their folds and {FIRST_ROUND} "
            f"folds of the rest): {floor:.3f} of the full run's seconds"
        )
        print(f"  full top 5 live at the end of the race: {len(top_live)}/5 ({', '.join(top)})")
        not_worse = [row.classifier for row in full_board.rows if row.mark != "*"]
        lost = [entry for entry in not_worse if entry in drops]
        print(
            f"  entries the full run does not mark significantly worse than its winner, live "
            f"at the end: {len(not_worse) - len(lost)}/{len(not_worse)} "
            f"({', '.join(not_worse)}; dropped: {', '.join(lost) or 'none'})"
        )
        print(
            f"  winner: full {full_best.classifier} {full_best.metrics[metric][0]:.4f}, "
            f"raced {raced_best.classifier} {raced_best.metrics[metric][0]:.4f}; "
            f"difference {difference:.4f} (goal <= 0.005)"
        )
        scores = per_fold(full, metric)
        lower = race.lower_is_better
        for name, dropped in (
            ("t-test vs leader", replay_ttest(scores, metric, args.alpha, ratio, len(folds))),
            ("Friedman/Nemenyi", replay_nemenyi(scores, lower, args.alpha, len(folds))),
        ):
            saved = sum(len(folds) - k for k in dropped.values())
            lost = [entry for entry in top if entry in dropped]
            print(
                f"  replay {name}: {len(dropped)} dropped, {saved}/{len(full)} tasks "
                f"saved, top 5 dropped: {', '.join(lost) or 'none'}"
            )
        live = len(ids)
        print(
            "  Nemenyi critical difference at alpha "
            f"{args.alpha:g} with {live} entries: "
            + ", ".join(
                f"{nemenyi_cd(live, n, args.alpha):.1f} after {n} folds"
                for n in sorted({FIRST_ROUND, len(folds)})
            )
            + f" (mean ranks differ by {live - 1} at most)"
        )
        if args.budget_fraction:
            budget = full_wall * args.budget_fraction
            cut, cuts, cut_wall = timed(
                problem, ids, folds, args.jobs, random_state=args.seed, budget=budget
            )
            complete = Counter(r.key.classifier for r in cut)
            whole = [e for e in top if complete[e] == len(folds)]
            print(
                f"  budget {budget:.1f} s ({args.budget_fraction:g} x full): ended after "
                f"{cut_wall:.1f} s, {len(cut)}/{len(full)} tasks, {len(cuts)} entries cut, "
                f"full top 5 with every fold: {len(whole)}/5"
            )
    return 0


#: Rows of ``--quick``: a subset of each data set, every k-th row.
QUICK_ROWS = 600
#: Added to ``--quick``'s fast suite.
QUICK_ENSEMBLES = ("voting", "voting-hard")


def child(args: argparse.Namespace) -> int:
    """One measured run in this process, with whatever code ``PYTHONPATH`` names; prints
    one JSON line: wall seconds, tasks, the leaderboard's rows (mean, mark against the
    winner, origin), drops and the selection's weights."""
    import importlib
    import json

    package = os.environ["RACING_PACKAGE"]  # "benchmark" (older code) or "touchbench.benchmark"
    engine = importlib.import_module(f"{package}.run.engine")
    folds_module = importlib.import_module(f"{package}.run.folds")
    leaderboard = importlib.import_module(f"{package}.evaluation.leaderboard")
    catalogue = importlib.import_module(f"{package}.catalogue")
    estimators = importlib.import_module(f"{package}.estimators")
    io = importlib.import_module(f"{package}.io.arff")
    robot, task, mode = args.child.split(":")
    data = io.read_arff(DATASETS / robot / "gesture_and_place.arff")
    names = list(data.schema.target_names)
    target = data.schema.target_indices[names.index(task)]
    features = [i for i in range(data.schema.n_attributes) if i not in data.schema.target_indices]
    rows = np.arange(data.values.shape[0])
    if args.quick:
        rows = rows[:: max(1, rows.size // QUICK_ROWS)][:QUICK_ROWS]
    problem = engine.Problem(
        X=data.values[np.ix_(rows, features)],
        Y=data.values[rows][:, [target]].astype(np.int64),
        n_classes=(len(data.schema.targets[names.index(task)].values),),
        target_names=(task,),
    )
    suite_name = "fast" if args.quick else args.suite
    ids = [i for i in catalogue.suite(suite_name) if not estimators.reads_sequences(i)]
    if args.quick:  # the ensembles the issue redefines, whose cost and scores it measures
        ids += [i for i in QUICK_ENSEMBLES if i not in ids]
    folds = folds_module.make_folds(
        problem.Y, n_folds=3 if args.quick else args.folds, seed=args.seed, target_names=(task,)
    )[0]
    options: dict[str, Any] = {}
    if mode == "race":
        options["race"] = engine.RaceRule("f1_weighted", args.alpha)
    elif mode == "ensemble":
        options["ensemble"] = args.ensemble
    drops: list[Any] = []
    start = time.perf_counter()
    results = engine.run_tasks(
        problem,
        ids,
        folds,
        jobs=args.jobs,
        timeout=TIMEOUT,
        random_state=args.seed,
        on_drop=drops.append,
        **options,
    )
    wall = time.perf_counter() - start
    board = leaderboard.build_leaderboard(
        results, metric="f1_weighted", drops={d.classifier: d for d in drops}
    )
    weights = [r.params for r in results if r.key.classifier.startswith("ensemble-") and r.params]
    # entries computed from fold predictions (this code; the older code fitted them all)
    plan_run = getattr(engine, "plan_run", None)
    computed = (
        list(plan_run(problem, ids, ensemble=options.get("ensemble")).derived)
        if plan_run is not None
        else []
    )
    print(
        json.dumps(
            {
                "wall": wall,
                "tasks": len(results),
                "failed": sum(1 for r in results if not r.ok),
                "error": next((r.error for r in results if not r.ok), None),
                "entries": len(ids),
                "rows": [
                    {
                        "classifier": row.classifier,
                        "mean": row.metrics.get("f1_weighted", (math.nan,))[0],
                        "mark": row.mark,
                        "dropped": row.dropped is not None,
                    }
                    for row in board.rows
                ],
                "weights": weights,
                "computed": computed,
            },
            default=str,
        )
    )
    return 0


def _measure(args: argparse.Namespace, code: str, package: str, job: str) -> dict[str, Any]:
    """A child run (``job`` = ROBOT:TASK:MODE) of the code in folder ``code``."""
    import json
    import subprocess

    command = [sys.executable, __file__, "--child", job, "--jobs", str(args.jobs)]
    command += ["--folds", str(args.folds), "--seed", str(args.seed), "--suite", args.suite]
    command += ["--alpha", str(args.alpha), "--ensemble", str(args.ensemble)]
    command += ["--quick"] if args.quick else []
    environment = {
        **os.environ,
        "PYTHONPATH": code,
        "RACING_PACKAGE": package,
        "TOUCHBENCH_DATASETS": str(DATASETS.parent),
    }
    # in the code's folder: worker processes put their working directory on the path, and
    # another worktree's top-level packages there would shadow the code measured
    done = subprocess.run(
        command, env=environment, capture_output=True, text=True, check=False, cwd=code
    )
    if done.returncode != 0:
        raise SystemExit(f"{job} with {code} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def side_by_side(args: argparse.Namespace) -> int:
    """Issue 35's table: the older code's full run against this code's full, raced and
    selecting runs, alternating, per data set (one Markdown row each)."""
    import json

    older = str(Path(args.against).resolve())
    package = "touchbench.benchmark" if (Path(older) / "touchbench").is_dir() else "benchmark"
    here = str(Path(__file__).resolve().parents[1])
    header = (
        "| data | older full s | full s (ratio) | race s (ratio) | ensemble s (/ full) "
        "| winner older / full / race | redefined ensembles moved | race kept the not-worse "
        f"| ensemble-{args.ensemble} vs best single |"
    )
    print(header)
    print("|" + "---|" * header.count(" | ") + "---|")
    for robot in args.robots.split(","):
        for task in args.tasks.split(","):
            if "+" in task:
                continue  # the selection and the votes are multi-class: one target
            walls: dict[str, list[float]] = {}
            last: dict[str, dict[str, Any]] = {}
            order = [
                ("older", older, package, "full"),
                ("full", here, "touchbench.benchmark", "full"),
                ("race", here, "touchbench.benchmark", "race"),
                ("ensemble", here, "touchbench.benchmark", "ensemble"),
            ][: 4 if args.ensemble else 3]
            if args.race_only:
                order = [order[0], order[2]]
            for round_ in range(args.rounds):
                for name, code, pkg, mode in order if round_ % 2 == 0 else order[::-1]:
                    found = _measure(args, code, pkg, f"{robot}:{task}:{mode}")
                    walls.setdefault(name, []).append(found["wall"])
                    if args.keep:
                        with open(args.keep, "a") as kept:
                            kept.write(json.dumps({"run": f"{robot}:{task}:{name}", **found}))
                            kept.write("\n")
                    last[name] = found
                    print(
                        f"  {robot} {task} {name}: {found['wall']:.1f} s, {found['tasks']} tasks, "
                        f"{found['failed']} failed {found['error'] or ''}",
                        file=sys.stderr,
                    )
                    if found["failed"] == found["tasks"]:
                        raise SystemExit(f"every task of {name} failed: {found['error']}")
            wall = {name: float(np.median(values)) for name, values in walls.items()}
            # each pass's race against the older run of the same pass: the machine's speed
            # drifts from minute to minute, less within a pass than across passes
            paired = [r / o for r, o in zip(walls["race"], walls["older"], strict=True)]
            print(
                f"  {robot} {task}: race / older full, pass by pass: "
                + ", ".join(f"{ratio:.3f}" for ratio in paired)
                + f" (median {np.median(paired):.3f})",
                file=sys.stderr,
            )
            if args.race_only:
                print(
                    f"| {robot} {task} | {wall['older']:.1f} | not run "
                    f"| {wall['race']:.1f} ({wall['race'] / wall['older']:.3f}) | not run "
                    f"| {last['older']['rows'][0]['classifier']} / - / "
                    f"{last['race']['rows'][0]['classifier']} | - | - | not run |"
                )
                continue
            means = {n: {r["classifier"]: r for r in found["rows"]} for n, found in last.items()}
            winners = {n: found["rows"][0]["classifier"] for n, found in last.items()}
            moved = [
                f"{c} {means['full'][c]['mean'] - means['older'][c]['mean']:+.4f}"
                for c in last["full"]["computed"]
                if c in means["older"]
            ]
            not_worse = [c for c, row in means["full"].items() if row["mark"] != "*"]
            lost = [c for c in not_worse if means["race"].get(c, {}).get("dropped", True)]
            selection = f"ensemble-{args.ensemble}"
            selected = means.get("ensemble", {})
            chosen = selected.get(selection, {}).get("mean", math.nan)
            others = [r["mean"] for c, r in selected.items() if c != selection]
            single = max(others, default=math.nan)
            ensemble = (
                f"{wall['ensemble']:.1f} ({wall['ensemble'] / wall['full']:.2f})"
                if args.ensemble
                else "not run"
            )
            versus = (
                f"{chosen:.4f} vs {single:.4f} ({'>=' if chosen >= 0.88 else '<'} 0.88)"
                if args.ensemble
                else "not run"
            )
            print(
                f"| {robot} {task} | {wall['older']:.1f} "
                f"| {wall['full']:.1f} ({wall['full'] / wall['older']:.3f}) "
                f"| {wall['race']:.1f} ({wall['race'] / wall['older']:.3f}) "
                f"| {ensemble} "
                f"| {winners['older']} / {winners['full']} / {winners['race']} "
                f"| {', '.join(moved) or 'none'} "
                f"| {'yes' if not lost else 'no: ' + ', '.join(lost)} "
                f"| {versus} |"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
