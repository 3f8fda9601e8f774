#!/usr/bin/env bash
# Makes sure a PostgreSQL server answers on 127.0.0.1:5432 with a database 'test' that the
# user postgres (password postgres) may use: installs it from Debian's packages if absent,
# starts the cluster if it is down. Exits 1 if no server can be had (the tests then skip
# their PostgreSQL leg and say why).
set -uo pipefail

ready() { pg_isready -q -h 127.0.0.1 -p 5432 2>/dev/null; }
as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

if ! command -v pg_ctlcluster >/dev/null 2>&1; then
  echo "installing PostgreSQL from Debian's packages" >&2
  as_root apt-get update -qq && as_root env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -qq postgresql >/dev/null || exit 1
fi
if ! ready; then
  version=$(ls /etc/postgresql 2>/dev/null | sort -V | tail -n 1)
  [ -n "$version" ] || exit 1
  as_root pg_ctlcluster --skip-systemctl-redirect "$version" main start >/dev/null 2>&1 || true
  for _ in $(seq 1 30); do ready && break; sleep 1; done
fi
ready || exit 1

# A fresh Debian install asks for passwords over TCP: give the test user one it knows.
if ! PGPASSWORD=postgres psql -h 127.0.0.1 -U postgres -d postgres -Atqc 'select 1' >/dev/null 2>&1; then
  as_root su postgres -c "psql -qc \"ALTER USER postgres PASSWORD 'postgres'\"" >/dev/null || exit 1
fi
PGPASSWORD=postgres psql -h 127.0.0.1 -U postgres -d postgres -Atqc \
  "select 1 from pg_database where datname = 'test'" | grep -q 1 \
  || PGPASSWORD=postgres createdb -h 127.0.0.1 -U postgres test || exit 1
