"""Carrying out queued work in worker processes: the dispatcher that a service process runs
(:mod:`~app.jobs.dispatcher`, wiring :mod:`~app.jobs.leadership`, :mod:`~app.jobs.queue` and
:mod:`~app.jobs.supervisor`), and the worker process entry point
(``python -m app.jobs.process``)."""
