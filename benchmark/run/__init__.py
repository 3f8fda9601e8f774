"""Carrying out a cross-validation: folds, the task (one classifier on one fold), the
result records, the local worker processes and the Dask backend, and the engine that
schedules tasks and reports each result as it arrives.

:mod:`benchmark.run.records` holds the result types and imports neither scikit-learn nor
the engine, so that the store and the CLI can read results without the start-up cost.
"""
