"""The benchmark package's exception tree.

Every problem caused by the user's input (a malformed file, an unknown classifier id,
an impossible fold count) is a :class:`BenchmarkError`; the CLI and the API turn it
into one clear line (exit status 2, HTTP 4xx).  Anything else is a bug.
"""

from __future__ import annotations


class BenchmarkError(Exception):
    """Bad input detected by the benchmark package."""


class DataFormatError(BenchmarkError):
    """A data file (ARFF, CSV) that cannot be read as it stands.

    Parameters
    ----------
    message : str
        What is wrong.
    source : str, optional
        The file's name.
    line : int, optional
        1-based line number in the file.
    attribute : str, optional
        The attribute (column) concerned.
    """

    def __init__(
        self,
        message: str,
        *,
        source: str | None = None,
        line: int | None = None,
        attribute: str | None = None,
    ) -> None:
        self.message = message
        self.source = source
        self.line = line
        self.attribute = attribute
        super().__init__(str(self))

    def __str__(self) -> str:
        where = ""
        if self.source is not None:
            where = self.source
            if self.line is not None:
                where += f":{self.line}"
            where += ": "
        elif self.line is not None:
            where = f"line {self.line}: "
        if self.attribute is not None:
            where += f"attribute '{self.attribute}': "
        return where + self.message


class ConfigurationError(BenchmarkError):
    """A benchmark asked for something that does not exist or cannot work.

    Examples: an unknown classifier or target, more folds than the smallest class allows.
    """


class DataWarning(UserWarning):
    """A data file read as it stands, with a choice the user should hear about.

    Example: a CSV column typed nominal because of a few words among numbers.  Callers
    that import data show these warnings as notes.
    """
