#!/usr/bin/env bash
# A throw-away PostgreSQL server for tests: the Debian package's initdb/pg_ctl in a folder of the
# test's own, on a free loopback port, stopped afterwards. Nothing is mocked.
#   pg_server.sh start DIR   initdb DIR/data, start; prints the port; superuser "calbench_admin"
#                            over the Unix socket in DIR (trust), passwords (SCRAM) over TCP 127.0.0.1
#   pg_server.sh stop DIR    fast shutdown (also the best-effort cleanup of a failed test)
#                            (again on the port it had before when that port is free: clients that
#                            reconnect to the same URI find it after a restart)
#   pg_server.sh kill DIR    SIGKILL the postmaster and all its processes at once, as a crash of the
#                            server would (for crash tests; then `start` again on the same DIR)
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
    free_port() { python3 -c 'import socket, sys; s=socket.socket(); s.bind(("127.0.0.1", int(sys.argv[1]))); print(s.getsockname()[1])' "$1" 2>/dev/null; }
    for attempt in 1 2 3 4 5; do
      port=
      # A restart keeps the port (the Unix socket's name carries it) unless another program took it.
      [ "$attempt" = 1 ] && [ -f "$dir/port" ] && port=$(free_port "$(cat "$dir/port")") || true
      [ -n "$port" ] || port=$(free_port 0)
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
    pm=$(head -1 "$dir/data/postmaster.pid")
    # The postmaster and its backends, checkpointer, WAL writer... in one go: nothing gets to
    # finish a commit or flush anything after this.
    procs="$pm $(pgrep -P "$pm" | tr '\n' ' ')"
    kill -9 $procs 2>/dev/null || true
    # Wait until every one is gone and reaped (a new postmaster refuses to start while the old
    # one's PID still exists, even as a zombie, or its shared memory is still attached).
    for _ in $(seq 200); do
      alive=0
      for p in $procs; do kill -0 "$p" 2>/dev/null && alive=1; done
      [ "$alive" = 0 ] && break
      sleep 0.05
    done
    ;;
  *) echo "pg_server.sh: unknown command '$cmd'" >&2; exit 2 ;;
esac
