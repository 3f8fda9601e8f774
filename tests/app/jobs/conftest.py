"""The real service's fixtures, for the tests of job processes that a service starts."""

from tests.app.api.conftest import make_sqlite_server  # noqa: F401 (a fixture)
