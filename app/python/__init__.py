"""touchbench from a researcher's own Python: the third adapter beside the CLI and the
service, over the same request types and services (``touchbench.bench``,
``touchbench.Client``, :class:`~app.python.leaderboard.Leaderboard`)."""
