"""Carrying out a cross-validation.

- :mod:`benchmark.run.engine`: :func:`~benchmark.run.engine.run_tasks`, the entry point;
  checks the classifiers and limits, lists the tasks (one classifier on one fold) and hands
  them to a backend, reporting each result as it arrives.
- :mod:`benchmark.run.backend`: the :class:`~benchmark.run.backend.Backend` interface, the
  :class:`~benchmark.run.backend.RunStopped` signal, and the outcomes every backend words
  the same way (a timeout, a worker that could not start).
- :mod:`benchmark.run.local_backend` and :mod:`benchmark.run.dask_backend`: the two
  backends, worker processes of this machine or of a Dask distributed cluster.
- :mod:`benchmark.run.worker`: a worker process that holds the run's data and runs tasks.
- :mod:`benchmark.run.task`: one task, run in the current process.
- :mod:`benchmark.run.folds`: the folds; :mod:`benchmark.run.choices`: what a tuned twin or
  a stack chose on a fold.

The result records live in :mod:`benchmark.results`, which imports neither scikit-learn nor
the engine, so that the store and the CLI can read results without the start-up cost.
"""
