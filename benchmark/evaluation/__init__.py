"""Judging results: per-fold metrics, WEKA's corrected resampled t-test, leaderboards,
WEKA Experimenter's results ARFF, and statistics across data sets.

Everything here works on result records and score arrays; it never imports
:mod:`benchmark.run` (an import-linter contract keeps it so), so results loaded from a
store can be judged without the engine.
"""
