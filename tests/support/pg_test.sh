# Sourced by the PostgreSQL CLI tests: a temporary folder $T, a throw-away server in $T/pg on a
# free loopback port ($port; stopped and removed on exit), `fail`, and `admin` (psql as the
# superuser calbench_admin over the Unix socket). Exits 77 (ctest: skipped) without PostgreSQL.
set -euo pipefail
T=$(mktemp -d)
cleanup() { "$SRC/tests/support/pg_server.sh" stop "$T/pg" || true; rm -rf "$T"; }
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
port=$("$SRC/tests/support/pg_server.sh" start "$T/pg") || { rc=$?; [ "$rc" = 77 ] && { echo "SKIP: no PostgreSQL"; exit 77; }; exit "$rc"; }
admin() { psql -h "$T/pg" -p "$port" -U calbench_admin -v ON_ERROR_STOP=1 -qtAX "$@"; }
