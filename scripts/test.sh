#!/usr/bin/env bash
# Sets touchbench up (scripts/install.sh), starts PostgreSQL for the store tests, then runs
# every check: ruff (lint and format), mypy, the import-linter layering contract, and pytest
# (every store test on both SQLite and PostgreSQL) in three worker processes (pytest-xdist;
# each has its own PostgreSQL database and temporary folders; a worker that runs out of tests
# takes half of the busiest one's, as the tests last from milliseconds to minutes). Extra
# arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install.sh
if bash scripts/postgres.sh; then
  export TOUCHBENCH_TEST_POSTGRES_URL=${TOUCHBENCH_TEST_POSTGRES_URL:-postgresql://postgres:postgres@127.0.0.1:5432/test}
else
  echo "no PostgreSQL server could be started: the PostgreSQL leg of the tests will skip" >&2
  export TOUCHBENCH_TEST_POSTGRES_URL=""
fi

echo "== ruff" && .venv/bin/ruff check . && .venv/bin/ruff format --check .
echo "== mypy" && .venv/bin/mypy
echo "== import-linter" && .venv/bin/lint-imports
echo "== pytest" && .venv/bin/pytest -n "${TOUCHBENCH_TEST_WORKERS:-3}" --dist worksteal "$@"
