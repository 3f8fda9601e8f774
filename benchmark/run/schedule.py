"""Which task a free worker starts next: the order of a run's tasks, its race and its budget.

A backend asks its :class:`TaskSource` for a task whenever a worker is free, and hands every
result back through the engine, so that what starts next may depend on what has finished.

- :class:`TaskList`: a fixed order (classifier-major, what a plain run does).
- :class:`RoundSchedule`: fold-major rounds (every live entry on fold 1, then fold 2, ...);
  with a :class:`~benchmark.run.racing.RaceRule` the entries significantly worse than the
  leader are dropped after each round from the third, and the entries the last decision
  found far from a drop run ahead of the next one instead of leaving workers idle while a
  round's dearest task finishes (a race starts the dear entries of a round first); with a
  budget, tasks whose predicted cost does not fit the time left are not started (cheap
  entries first).

A race's decisions depend on the scores alone: a result of round ``r + 1`` of an entry is
held back until the decision after round ``r`` is made, and dropped with its entry, so that
the results handed on (and stored) are the same whatever the timing, and a resumed race
replays the decisions of the stored results and goes on where it stopped.

Entries computed from others' folds (an ensemble of entries, a stack: ``derived``) have no
task of their own: their results arrive when their members' have (the engine computes them)
and race like any other's.  A member runs while it is live or while a live derived entry
needs it: a member the race dropped still runs for a live ensemble, its later results only
feeding the ensemble; a helper (a member the run did not ask for) is not raced, and its
results are handed on for the rounds where an entry that needs it was live.
"""

from __future__ import annotations

import statistics
import time
from collections import deque
from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Protocol, runtime_checkable

from touchbench.benchmark.results import Drop, TaskKey, TaskResult
from touchbench.benchmark.run.racing import RaceRule, race_round

__all__ = ["RoundSchedule", "TaskList", "TaskSource"]

#: A task's predicted cost is its entry's timed folds' mean, or the entry's hint times how
#: much slower the timed entries ran than their hints: this machine's speed, at least this.
MIN_CALIBRATION = 0.05
#: An entry whose p-value against the leader at the race's last decision is above this
#: (the leaderboard's own level) may start folds beyond the next decision's round.
SAFE_P = 0.05


@runtime_checkable
class TaskSource(Protocol):
    """The tasks a backend runs, handed out one at a time."""

    def next_task(self) -> TaskKey | None:
        """The task to start now; ``None`` when none may start until a result arrives."""
        ...

    @property
    def exhausted(self) -> bool:
        """Whether no task will ever start again."""
        ...

    def remaining(self) -> int:
        """Tasks that may still start, at most (how many workers are worth starting)."""
        ...


class TaskList:
    """Tasks in a fixed order."""

    def __init__(self, tasks: Sequence[TaskKey]) -> None:
        self._queue = deque(tasks)

    def next_task(self) -> TaskKey | None:
        return self._queue.popleft() if self._queue else None

    @property
    def exhausted(self) -> bool:
        return not self._queue

    def remaining(self) -> int:
        return len(self._queue)


class RoundSchedule:
    """Fold-major rounds with an optional race and budget.

    Parameters
    ----------
    entries : sequence of str
        Classifier ids.
    rounds : sequence of (int, int)
        ``(repeat, fold)`` of each round, in order.
    deliver : callable
        Hears every result handed on (a race holds some back; see the module's notes).
    hints : mapping of str to float
        Predicted seconds of one fold per entry, before it has been timed.
    previous : sequence of TaskResult
        Results of a resumed run (not run again, not delivered again).
    done : collection of TaskKey
        Tasks of a resumed run done without their results at hand (not run again; a
        race needs ``previous`` instead, for its scores).
    race : RaceRule, optional
    test_train_ratio : float
        ``n_test / n_train`` of the folds, for the race's t-test.
    budget : float, optional
        Seconds from now after which no task may still be running by prediction.
    on_drop : callable, optional
        Hears each entry dropped by the race (at once) or cut by the budget (by
        :meth:`finish`).
    clock : callable
        Monotonic seconds (tests give their own).
    derived : mapping of str to collection of str
        Entries computed from others' folds, with every entry (among ``entries``) whose
        folds they are computed from, their members' members included.
    helpers : collection of str
        Entries the run did not ask for, members of derived ones: not raced.
    rerun : collection of TaskKey
        Tasks of ``done`` to run again (their predictions are needed and not at hand);
        their results do not come back here.
    """

    def __init__(
        self,
        entries: Sequence[str],
        rounds: Sequence[tuple[int, int]],
        deliver: Callable[[TaskResult], None],
        *,
        hints: Mapping[str, float],
        previous: Sequence[TaskResult] = (),
        done: Collection[TaskKey] = (),
        race: RaceRule | None = None,
        test_train_ratio: float = 0.0,
        budget: float | None = None,
        on_drop: Callable[[Drop], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
        derived: Mapping[str, Collection[str]] | None = None,
        helpers: Collection[str] = (),
        rerun: Collection[TaskKey] = (),
    ) -> None:
        self._entries = list(dict.fromkeys(entries))
        self._derived = {entry: frozenset(needs) for entry, needs in (derived or {}).items()}
        self._helpers = frozenset(helpers)
        self._rounds = {key: index for index, key in enumerate(rounds)}
        self._n_rounds = len(rounds)
        self._round_keys = list(rounds)
        self._deliver = deliver
        self._hints = dict(hints)
        self._race = race
        self._ratio = test_train_ratio
        self._on_drop = on_drop or (lambda drop: None)
        self._clock = clock
        self._deadline = None if budget is None else clock() + budget
        self._live = [e for e in self._entries if e not in self._helpers]
        self._arrived: dict[str, set[int]] = {e: set() for e in self._entries}
        self._started: dict[str, set[int]] = {e: set() for e in self._entries}
        self._scores: dict[str, dict[int, float]] = {e: {} for e in self._entries}
        self._held: list[TaskResult] = []
        self._began: dict[TaskKey, float] = {}
        self._seconds: dict[str, list[float]] = {}
        self._cut: set[str] = set()
        #: the last decision's leader and each survivor's p-value against it
        self._leader: str | None = None
        self._p_values: dict[str, float] = {}
        #: rounds up to this index are decided; the next one is certain, the one after
        #: may start ahead of the decision (its results are held back)
        self._decided = race.first_round - 2 if race is not None else self._n_rounds
        self.dropped: dict[str, Drop] = {}
        for result in previous:
            self._note(result)
        for key in done:
            if key.classifier in self._arrived and (key.repeat, key.fold) in self._rounds:
                self._arrived[key.classifier].add(self._rounds[(key.repeat, key.fold)])
        for entry in self._entries:
            self._started[entry] = set(self._arrived[entry])
        for key in rerun:
            if key.classifier in self._started and (key.repeat, key.fold) in self._rounds:
                self._started[key.classifier].discard(self._rounds[(key.repeat, key.fold)])
        self._make_decisions()

    # the backend's side -------------------------------------------------------------

    def next_task(self) -> TaskKey | None:
        """The next fold of the live entry that is furthest behind and may start, if any.

        Ties within a round: without a budget the dear entries start first (a race's
        decision waits for the round's last task, and a derived entry for its members': a
        long one started last leaves the other workers idle at the end of the round); a
        budget starts the cheap ones first (more entries complete before it runs out).
        """
        now = self._clock()
        calibration = self._calibration()  # once per call: it reads every timed entry
        order = -1.0 if self._deadline is None else 1.0
        waiting = []
        for position, entry in enumerate(self._active()):
            index = next(
                (i for i in range(self._horizon(entry) + 1) if i not in self._started[entry]),
                None,
            )
            if index is not None:
                cost = self._cost(entry, calibration)
                waiting.append((index, order * cost, position, entry, cost))
        for index, _, _, entry, cost in sorted(waiting):  # ties: the run's order
            if entry not in self._active():
                continue  # a budget's cut below let the race decide and drop it
            if self._deadline is not None and now + cost > self._deadline:
                self._cut_entry(entry)
                continue
            self._started[entry].add(index)
            key = TaskKey(entry, *self._round_keys[index])
            self._began[key] = now
            return key
        return None

    def _horizon(self, entry: str) -> int:
        """The last round ``entry`` may start now.

        A race's next decision waits for every live entry's round after the last decision;
        the round after that may start too (its results are held back until the decision).
        An entry the last decision found far from a drop (the leader, the protected ones,
        p-value against the leader above :data:`SAFE_P`) may run further ahead: a worker
        that would wait for the slowest entry of the round works on a fold the race will
        most probably keep.  Only the timing depends on it, not what is stored.  An entry a
        live derived entry needs may go as far as that entry may.
        """
        users = [e for e in self._live if e == entry or entry in self._derived.get(e, ())]
        return max((self._own_horizon(e) for e in users), default=-1)

    def _own_horizon(self, entry: str) -> int:
        """The last round a live entry's folds may start (see :meth:`_horizon`)."""
        last = self._n_rounds - 1
        if self._race is None or self._deadline is not None:
            return last if self._race is None else min(self._decided + 2, last)
        if entry == self._leader or entry in self._race.protected:
            return last
        p = self._p_values.get(entry)
        if p is not None and p > SAFE_P:
            return last
        return min(self._decided + 2, last)

    def _active(self) -> list[str]:
        """The entries with tasks to start: the live ones, and those a live derived entry
        needs (a helper, a member the race dropped), in the run's order."""
        needed = set().union(*(self._derived.get(e, ()) for e in self._live))
        return [
            e
            for e in self._entries
            if e not in self._derived and e not in self._cut and (e in self._live or e in needed)
        ]

    @property
    def exhausted(self) -> bool:
        return self.remaining() == 0

    def remaining(self) -> int:
        if self._deadline is not None and self._clock() >= self._deadline:
            for entry in self._active():  # nothing fits any more: no worker need start
                if entry not in self._cut and len(self._started[entry]) < self._n_rounds:
                    self._cut_entry(entry)
        return sum(self._n_rounds - len(self._started[e]) for e in self._active())

    def arrived(self, result: TaskResult) -> None:
        """Take a result: hand it on (or hold it back), and decide the rounds it completes."""
        began = self._began.pop(result.key, None)
        if began is not None:
            self._seconds.setdefault(result.key.classifier, []).append(self._clock() - began)
        if result.key.classifier in self.dropped:
            return  # started ahead of the decision that dropped it, or run for an ensemble
        index = self._note(result)
        if index > self._decided + 1:
            self._held.append(result)
        else:
            self._hand_on(result, index)
        self._make_decisions()

    def _hand_on(self, result: TaskResult, index: int) -> None:
        """Deliver a result, but a helper's only for a round where an entry that needs it
        was live (the decisions up to the round before it are made)."""
        entry = result.key.classifier
        if entry in self._helpers and not any(
            entry in needs and (d not in self.dropped or self.dropped[d].after_fold > index)
            for d, needs in self._derived.items()
        ):
            return
        self._deliver(result)

    def cost(self, entry: str) -> float:
        """Predicted seconds of one more fold of ``entry``."""
        return self._cost(entry, self._calibration())

    # the race ------------------------------------------------------------------------

    def _note(self, result: TaskResult) -> int:
        entry, index = result.key.classifier, self._rounds[(result.key.repeat, result.key.fold)]
        self._arrived.setdefault(entry, set()).add(index)
        if entry in self._derived:  # it has no task: it started when it arrived
            self._started.setdefault(entry, set()).add(index)
        metric = self._race.metric if self._race is not None else None
        value = result.metrics.get(metric) if metric is not None and result.ok else None
        if value is not None and value == value:  # not NaN
            self._scores.setdefault(entry, {})[index] = float(value)
        return index

    def _make_decisions(self) -> None:
        while self._race is not None and self._decided + 1 < self._n_rounds:
            index = self._decided + 1
            # every round up to this one: the first decision covers the rounds before it
            if any(len(self._arrived[e] & set(range(index + 1))) <= index for e in self._live):
                return
            scores = {
                e: {r: s for r, s in self._scores[e].items() if r <= index} for e in self._live
            }
            outcome = race_round(
                self._race, scores, self._live, index, test_train_ratio=self._ratio
            )
            self._leader, self._p_values = outcome.leader, outcome.p_values
            for drop in outcome.drops:
                self.dropped[drop.classifier] = drop
                self._live.remove(drop.classifier)
                self._on_drop(drop)
            self._decided = index
            self._release()

    def _release(self) -> None:
        """Hand on the held results the decisions now allow; forget the dropped entries'."""
        held, self._held = self._held, []
        for result in held:
            entry = result.key.classifier
            index = self._rounds[(result.key.repeat, result.key.fold)]
            if entry in self.dropped:
                self._arrived[entry].discard(index)
                self._scores[entry].pop(index, None)
            elif index > self._decided + 1:
                self._held.append(result)
            else:
                self._hand_on(result, index)

    # the budget ------------------------------------------------------------------------

    def _cost(self, entry: str, calibration: float) -> float:
        timed = self._seconds.get(entry)
        if timed:
            return statistics.fmean(timed)
        return self._hints.get(entry, 1.0) * calibration

    def _calibration(self) -> float:
        ratios = [
            statistics.fmean(s) / self._hints[e]
            for e, s in self._seconds.items()
            if s and self._hints.get(e, 0) > 0
        ]
        return max(statistics.median(ratios), MIN_CALIBRATION) if ratios else 1.0

    def _cut_entry(self, entry: str) -> None:
        """Start no more of ``entry``'s tasks, nor the folds of the live entries made of it."""
        users = [d for d in self._live if entry in self._derived.get(d, ())]
        for cut in [entry, *users]:
            self._cut.add(cut)
            if cut in self._live:
                self._live.remove(cut)
        self._make_decisions()

    def cut_tasks(self) -> int:
        """Tasks the budget did not start."""
        return sum(self._n_rounds - len(self._started[e]) for e in self._cut)

    def finish(self) -> None:
        """The backend is done: hand on what the race still holds of entries it did not
        drop (a budget cut the entries its next decision waited for), and report the
        budget's cuts with the folds each entry ran."""
        held, self._held = self._held, []
        for result in held:
            if result.key.classifier not in self.dropped:
                self._hand_on(result, self._rounds[(result.key.repeat, result.key.fold)])
        for entry in self._entries:
            if entry in self._cut and entry not in self.dropped:
                self._on_drop(Drop(entry, "budget", len(self._arrived[entry])))


def test_train_ratio(sizes: Collection[tuple[int, int]]) -> float:
    """Mean ``n_test / n_train`` of folds given as ``(n_train, n_test)``."""
    ratios = [test / train for train, test in sizes if train > 0]
    return statistics.fmean(ratios) if ratios else 0.0
