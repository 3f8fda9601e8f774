#!/usr/bin/env bash
# Sets touchbench up (scripts/install.sh), starts PostgreSQL for the store tests, then runs
# every check: ruff (lint and format), the import-linter layering contract, mypy, and pytest
# (every store test on both SQLite and PostgreSQL) in three worker processes (pytest-xdist;
# each has its own PostgreSQL database and temporary folders; a worker that runs out of tests
# takes half of the busiest one's, as the tests last from milliseconds to minutes). Extra
# arguments go to pytest. Any check that fails fails the command, after pytest has run.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install.sh
# The suite starts hundreds of Python processes (services, jobs, engine workers, the CLI)
# and three pytest workers that each rewrite every test module's assertions: all of them
# keep their bytecode in __pycache__ (git ignores it) rather than compiling it again, even
# where the environment says PYTHONDONTWRITEBYTECODE.
unset PYTHONDONTWRITEBYTECODE
if bash scripts/postgres.sh; then
  export TOUCHBENCH_TEST_POSTGRES_URL=${TOUCHBENCH_TEST_POSTGRES_URL:-postgresql://postgres:postgres@127.0.0.1:5432/test}
else
  echo "no PostgreSQL server could be started: the PostgreSQL leg of the tests will skip" >&2
  export TOUCHBENCH_TEST_POSTGRES_URL=""
fi

# Each check on its own line: under `set -e`, a failure inside an `a && b` list is not fatal.
echo "== ruff"
.venv/bin/ruff check .
.venv/bin/ruff format --check .
echo "== import-linter"
.venv/bin/lint-imports
# mypy takes one core for most of a minute: it runs beside pytest, whose workers leave part
# of the cores idle while they wait on the services and processes they start.
typed=$(mktemp)
trap 'rm -f "$typed"' EXIT
.venv/bin/mypy >"$typed" 2>&1 &
mypy=$!
echo "== pytest"
status=0
.venv/bin/pytest -n "${TOUCHBENCH_TEST_WORKERS:-3}" --dist worksteal "$@" || status=$?
echo "== mypy"
cat "$typed"
wait "$mypy" || status=$((status ? status : 1))
exit "$status"
