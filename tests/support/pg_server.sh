#!/usr/bin/env bash
# A throw-away PostgreSQL server for tests: the Debian package's initdb/pg_ctl in a folder of the
# test's own, on a free loopback port, stopped afterwards. Nothing is mocked.
#   pg_server.sh start DIR   initdb DIR/data, start; prints the port; superuser "calbench_admin"
#                            over the Unix socket in DIR (trust), passwords (SCRAM) over TCP 127.0.0.1
#   pg_server.sh stop DIR    fast shutdown (also the best-effort cleanup of a failed test)
#   pg_server.sh kill DIR    SIGKILL the postmaster (for crash tests; then `start` again on the same DIR)
# Run as root, the server runs as the unprivileged user "postgres" (from the package; else
# "nobody"): PostgreSQL refuses to run as root.
set -euo pipefail
cmd=${1:?usage: pg_server.sh start|stop|kill DIR}
dir=$(realpath -m "${2:?usage: pg_server.sh start|stop|kill DIR}")
bin=${PG_BIN:-$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)}
[ -x "$bin/initdb" ] || { echo "pg_server.sh: no PostgreSQL server binaries (apt install postgresql; scripts/setup)" >&2; exit 77; }
as_server() {
  if [ "$(id -u)" = 0 ]; then
    local u=postgres
    id "$u" >/dev/null 2>&1 || u=nobody
    runuser -u "$u" -- "$@"
  else
    "$@"
  fi
}
case "$cmd" in
  start)
    mkdir -p "$dir"
    if [ "$(id -u)" = 0 ]; then
      u=postgres; id "$u" >/dev/null 2>&1 || u=nobody
      chown "$u" "$dir"
      chmod 700 "$dir"
      # The server user must be able to reach DIR: let others traverse (not list) its parents
      # (a mktemp folder is 0700).
      p=$(dirname "$dir")
      while [ "$p" != / ]; do
        [ "$(stat -c %u "$p")" = 0 ] && chmod o+x "$p"
        p=$(dirname "$p")
      done
    fi
    if [ ! -f "$dir/data/PG_VERSION" ]; then
      as_server "$bin/initdb" -D "$dir/data" -U calbench_admin --auth-local=trust --auth-host=scram-sha-256 \
        --encoding=UTF8 --locale=C.UTF-8 >"$dir/initdb.log" 2>&1 || { cat "$dir/initdb.log" >&2; exit 1; }
    fi
    for attempt in 1 2 3 4 5; do
      port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
      if as_server "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
          -o "-c listen_addresses=127.0.0.1 -p $port -k $dir -c fsync=on -c max_connections=60" start >/dev/null; then
        echo "$port" > "$dir/port"
        echo "$port"
        exit 0
      fi
    done
    cat "$dir/server.log" >&2
    exit 1
    ;;
  stop)
    [ -f "$dir/data/postmaster.pid" ] || exit 0
    as_server "$bin/pg_ctl" -D "$dir/data" -m fast -w -t 60 stop >/dev/null 2>&1 || true
    ;;
  kill)
    [ -f "$dir/data/postmaster.pid" ] || exit 0
    kill -9 "$(head -1 "$dir/data/postmaster.pid")" 2>/dev/null || true
    # Its children notice the postmaster's death and exit; wait until the port is free.
    for _ in $(seq 50); do pgrep -f -- "-D $dir/data" >/dev/null || break; sleep 0.1; done
    ;;
  *) echo "pg_server.sh: unknown command '$cmd'" >&2; exit 2 ;;
esac
