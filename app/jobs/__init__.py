"""Carrying out queued work in worker processes: the dispatcher that a service process runs,
and the worker process entry point (``python -m app.jobs.process``)."""
