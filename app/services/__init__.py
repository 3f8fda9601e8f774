"""Every use case of touchbench, once: importing and describing data sets, extracting them
from recordings, creating and executing benchmark runs, training models and predicting.

The CLI (:mod:`app.cli`) and the service (:mod:`app.api`) are thin adapters over these
functions: they parse, call a service, and render its result (through :mod:`app.schemas`).
"""
