"""Named suites of multi-target configurations, like the catalogue's for multi-class."""

from __future__ import annotations

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.multitarget.registry import META_METHODS, multitarget_configurations

#: Quick configurations for smoke runs and the demo.
FAST = ("cr:nb", "bcc:nb", "cr:j48", "cc:j48", "bcc:j48", "lc:j48")
#: The paper's base (RandomForest) under every multi-target method, plus the strongest
#: other bases under the methods that use target dependencies.
DEFAULT_EXTRA = ("bcc:extra-trees", "cc:extra-trees", "lc:extra-trees", "bcc:xgb", "lc:xgb")


def multitarget_suite(name: str) -> list[str]:
    """The configuration ids of a suite.

    Parameters
    ----------
    name : {"fast", "default", "all"}
        ``fast``: six quick configurations; ``default``: every multi-target method over
        RandomForest plus a few ExtraTrees and XGBoost ones; ``all``: every method over
        every default base.
    """
    if name == "fast":
        return list(FAST)
    if name == "default":
        over_rf = [f"{m}:rf" for m, spec in META_METHODS.items() if not spec.binary_only]
        return over_rf + list(DEFAULT_EXTRA)
    if name == "all":
        return multitarget_configurations()
    raise ConfigurationError(f"unknown suite '{name}' (suites: fast, default, all)")
