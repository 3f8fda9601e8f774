"""WEKA command lines of the schemes touchbench reproduces: written, and read back.

A :class:`WekaScheme` knows one WEKA class: which catalogue entry holds its estimator,
which of WEKA's options touchbench supports and the estimator parameter each one sets,
and how WEKA writes them (the order of ``getOptions``), so that a catalogue entry states
exactly the command WEKA would run and a command from a user or from a WEKA results file
(``Key_Scheme`` + ``Key_Scheme_options``) turns into estimator parameters.  An option
touchbench does not support is refused by name.
"""

from __future__ import annotations

import shlex
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from touchbench.benchmark.errors import ConfigurationError

W = "weka.classifiers."

#: The only neighbour search IBk supports here, as WEKA writes it.
EUCLIDEAN_SEARCH = (
    'weka.core.neighboursearch.LinearNNSearch -A "weka.core.EuclideanDistance -R first-last"'
)


@dataclass(frozen=True)
class WekaOption:
    """One WEKA option and the estimator parameter it sets.

    Parameters
    ----------
    flag : str
        ``"-C"``.
    param : str or None
        The estimator parameter it sets; None for an option accepted only with the value
        WEKA uses by default (``accepted``).
    kind : {"flag", "int", "float", "fixed"}
        A switch, a number, or a value that must be one of ``accepted``.  A number with
        no ``param`` is checked and ignored (it does not change the model).
    set_to : Any
        For a switch: the parameter's value when the switch is present.
    accepted : tuple of str
        For ``"fixed"``: the values accepted (compared after WEKA's own quoting is read).
    low, high : float
        For numbers: the range touchbench accepts, ``low < value <= high``.
    """

    flag: str
    param: str | None
    kind: str
    set_to: Any = None
    accepted: tuple[str, ...] = ()
    low: float = 0.0
    high: float = float("inf")


@dataclass(frozen=True)
class WekaScheme:
    """A WEKA class that a catalogue entry reproduces.

    Parameters
    ----------
    weka_class : str
        ``"weka.classifiers.trees.J48"``.
    base_id : str
        The catalogue entry with WEKA's defaults; other option values derive from it.
    options : tuple of WekaOption
        Supported options.
    render : callable
        ``render(params) -> list of str``: the option tokens WEKA writes for these
        estimator parameters, in WEKA's order.
    check : callable, optional
        ``check(flags_present) -> None``: raises for combinations WEKA refuses.
    """

    weka_class: str
    base_id: str
    options: tuple[WekaOption, ...]
    render: Callable[[Mapping[str, Any]], list[str]]
    check: Callable[[set[str]], None] | None = None

    def command(self, params: Mapping[str, Any]) -> str:
        """The WEKA command line for estimator ``params`` (WEKA's option order)."""
        tokens = self.render(params)
        return " ".join([self.weka_class, *(_quote(t) for t in tokens)])

    def parse(self, tokens: Sequence[str]) -> dict[str, Any]:
        """Estimator parameters set by WEKA option ``tokens`` (already split).

        Raises
        ------
        ConfigurationError
            An option touchbench does not support, a missing or malformed value, or a
            combination WEKA refuses; the message names the option.
        """
        by_flag = {option.flag: option for option in self.options}
        params: dict[str, Any] = {}
        present: set[str] = set()
        i = 0
        while i < len(tokens):
            flag = tokens[i]
            option = by_flag.get(flag)
            if option is None:
                supported = " ".join(sorted(by_flag)) or "none"
                raise ConfigurationError(
                    f"{self.weka_class}: option '{flag}' is not supported by touchbench "
                    f"(supported: {supported})"
                )
            if flag in present:
                raise ConfigurationError(f"{self.weka_class}: option '{flag}' is given twice")
            present.add(flag)
            if option.kind == "flag":
                if option.param is not None:
                    params[option.param] = option.set_to
                i += 1
                continue
            if i + 1 >= len(tokens):
                raise ConfigurationError(f"{self.weka_class}: option '{flag}' needs a value")
            params.update(_value(self.weka_class, option, tokens[i + 1]))
            i += 2
        if self.check is not None:
            self.check(present)
        return params


def _value(weka_class: str, option: WekaOption, text: str) -> dict[str, Any]:
    where = f"{weka_class}: option '{option.flag} {text}'"
    if option.kind == "fixed":
        # the neighbour search and distance IBk uses by default; any other is refused
        if not any(_normalise(text) == _normalise(a) for a in option.accepted):
            allowed = " or ".join(repr(a) for a in option.accepted)
            raise ConfigurationError(f"{where} is not supported by touchbench (only {allowed})")
        return {}
    try:
        number: int | float = int(text) if option.kind == "int" else float(text)
    except ValueError:
        raise ConfigurationError(
            f"{where}: expected {'an integer' if option.kind == 'int' else 'a number'}"
        ) from None
    if not option.low < number <= option.high:
        limit = f"at most {option.high:g}" if number > option.high else f"above {option.low:g}"
        raise ConfigurationError(f"{where}: the value must be {limit}")
    return {} if option.param is None else {option.param: number}


def _normalise(text: str) -> list[str]:
    """Option text as nested tokens, so that quoting differences do not matter."""
    try:
        return shlex.split(text)
    except ValueError:
        return [text]


def _quote(token: str) -> str:
    """A token as WEKA writes it: double quotes around text with spaces, inner ones escaped."""
    if " " not in token and '"' not in token:
        return token
    return '"' + token.replace("\\", "\\\\").replace('"', '\\"') + '"'


def split_command(text: str) -> tuple[str, list[str]]:
    """``(class, option tokens)`` of a WEKA command line (WEKA's quoting rules).

    Raises
    ------
    ConfigurationError
        Empty text or unbalanced quotes.
    """
    try:
        tokens = shlex.split(text)
    except ValueError as exc:
        raise ConfigurationError(f"cannot read WEKA command line {text!r}: {exc}") from None
    if not tokens:
        raise ConfigurationError("empty WEKA command line")
    return tokens[0], tokens[1:]


# The schemes ---------------------------------------------------------------------------


def _j48_options(params: Mapping[str, Any]) -> list[str]:
    out: list[str] = []
    if not params.get("pruned", True):
        out.append("-U")
    else:
        if not params.get("subtree_raising", True):
            out.append("-S")
        out += ["-C", _float(params.get("confidence", 0.25))]
    out += ["-M", str(params.get("min_instances", 2))]
    if params.get("laplace", False):
        out.append("-A")
    return out


def _j48_check(present: set[str]) -> None:
    if "-U" in present and "-S" in present:
        raise ConfigurationError(
            "weka.classifiers.trees.J48: option '-S' (no subtree raising) makes no sense with "
            "'-U' (unpruned), as WEKA says"
        )
    if "-U" in present and "-C" in present:
        raise ConfigurationError(
            "weka.classifiers.trees.J48: option '-C' (pruning confidence) makes no sense with "
            "'-U' (unpruned), as WEKA says"
        )


def _part_options(params: Mapping[str, Any]) -> list[str]:
    minimum, confidence = params.get("min_instances", 2), params.get("confidence", 0.25)
    return ["-M", str(minimum), "-C", _float(confidence), "-Q", "1"]


def _naive_bayes_options(params: Mapping[str, Any]) -> list[str]:
    return {"kernel": ["-K"], "discretize": ["-D"]}.get(params.get("numeric", "normal"), [])


def _naive_bayes_check(present: set[str]) -> None:
    if {"-K", "-D"} <= present:
        raise ConfigurationError(
            "weka.classifiers.bayes.NaiveBayes: options '-K' and '-D' exclude each other"
        )


def _ibk_options(params: Mapping[str, Any]) -> list[str]:
    out = ["-K", str(params.get("n_neighbors", 1)), "-W", "0"]
    out += {"inverse": ["-I"], "similarity": ["-F"]}.get(params.get("weighting", "none"), [])
    return [*out, "-A", EUCLIDEAN_SEARCH]


def _ibk_check(present: set[str]) -> None:
    if {"-I", "-F"} <= present:
        raise ConfigurationError(
            "weka.classifiers.lazy.IBk: options '-I' and '-F' exclude each other"
        )


def _float(value: float) -> str:
    """A number as Java prints a float (``0.25``, ``0.1``, ``1.0``)."""
    return repr(float(value))


SCHEMES: tuple[WekaScheme, ...] = (
    WekaScheme(W + "rules.ZeroR", "zeror", (), lambda params: []),
    WekaScheme(
        W + "trees.J48",
        "j48",
        (
            WekaOption("-U", "pruned", "flag", False),
            WekaOption("-C", "confidence", "float", high=0.5),
            WekaOption("-M", "min_instances", "int"),
            WekaOption("-S", "subtree_raising", "flag", False),
            WekaOption("-A", "laplace", "flag", True),
        ),
        _j48_options,
        _j48_check,
    ),
    WekaScheme(
        W + "rules.PART",
        "part",
        (
            WekaOption("-M", "min_instances", "int"),
            WekaOption("-C", "confidence", "float", high=0.5),
            # the seed of reduced-error pruning, which touchbench does not offer: no effect
            WekaOption("-Q", None, "int", low=-float("inf")),
        ),
        _part_options,
    ),
    WekaScheme(
        W + "bayes.NaiveBayes",
        "nb",
        (
            WekaOption("-K", "numeric", "flag", "kernel"),
            WekaOption("-D", "numeric", "flag", "discretize"),
        ),
        _naive_bayes_options,
        _naive_bayes_check,
    ),
    WekaScheme(
        W + "lazy.IBk",
        "ibk",
        (
            WekaOption("-K", "n_neighbors", "int"),
            WekaOption("-I", "weighting", "flag", "inverse"),
            WekaOption("-F", "weighting", "flag", "similarity"),
            WekaOption("-W", None, "fixed", accepted=("0",)),
            WekaOption(
                "-A",
                None,
                "fixed",
                accepted=(EUCLIDEAN_SEARCH, "weka.core.neighboursearch.LinearNNSearch"),
            ),
        ),
        _ibk_options,
        _ibk_check,
    ),
)

_BY_CLASS = {scheme.weka_class: scheme for scheme in SCHEMES}


def scheme_for(weka_class: str) -> WekaScheme:
    """The scheme of a WEKA class, by full name (``weka.classifiers.trees.J48``) or last part.

    Raises
    ------
    ConfigurationError
        A class touchbench does not reproduce, naming those it does.
    """
    if weka_class in _BY_CLASS:
        return _BY_CLASS[weka_class]
    short = [s for s in SCHEMES if s.weka_class.rsplit(".", 1)[-1] == weka_class]
    if len(short) == 1:
        return short[0]
    known = ", ".join(s.weka_class for s in SCHEMES)
    raise ConfigurationError(
        f"touchbench does not reproduce WEKA's '{weka_class}' (it reproduces {known})"
    )


def weka_command(weka_class: str, params: Mapping[str, Any]) -> str:
    """The WEKA command line of a catalogue entry built on ``weka_class`` with ``params``."""
    return scheme_for(weka_class).command(params)
