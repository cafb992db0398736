#!/usr/bin/env bash
# A throw-away PostgreSQL cluster for the tests, run as the `postgres` user (PostgreSQL
# refuses to run as root) on a free local port.
#
#   eval "$(.ci/postgres.sh start DIR)"   starts a cluster in DIR (made, owned by postgres)
#                                         and prints `export MAZEARENA_TEST_POSTGRES=URL`
#   .ci/postgres.sh restart DIR           stops it at once (as a crash would) and starts it
#                                         again on the same port
#   .ci/postgres.sh crash DIR             only stops it at once (as a crash would)
#   .ci/postgres.sh resume DIR            starts a crashed cluster again on its port
#   .ci/postgres.sh stop DIR              stops it (fast shutdown) and removes DIR
#
# The URL names the `postgres` superuser (trust authentication on 127.0.0.1 only), so a
# test may create and drop a database of its own for each case.
set -euo pipefail
cmd=${1:?start or stop}
dir=${2:?the cluster folder}
bindir=$(pg_config --bindir 2>/dev/null || true)
if [ -z "$bindir" ] || [ ! -x "$bindir/initdb" ]; then
  bindir=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)
fi
[ -x "$bindir/initdb" ] || { echo "PostgreSQL's initdb was not found (install postgresql)" >&2; exit 1; }

as_postgres() {
  if [ "$(id -u)" = 0 ]; then
    runuser -u postgres -- "$@"
  else
    "$@"
  fi
}

case $cmd in
start)
  mkdir -p "$dir"
  [ "$(id -u)" = 0 ] && chown postgres: "$dir"
  as_postgres "$bindir/initdb" -D "$dir/data" -U postgres --auth=trust -E UTF8 >"$dir/initdb.log"
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  as_postgres "$bindir/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w \
    -o "-p $port -c listen_addresses=127.0.0.1 -k $dir -c max_connections=200 -c fsync=off" start >/dev/null
  echo "$port" >"$dir/port"
  echo "export MAZEARENA_TEST_POSTGRES=postgres://postgres@127.0.0.1:$port/postgres"
  echo "export MAZEARENA_TEST_POSTGRES_DIR=$dir"
  ;;
restart)
  "$0" crash "$dir"
  "$0" resume "$dir"
  ;;
crash)
  as_postgres "$bindir/pg_ctl" -D "$dir/data" -m immediate -w stop >/dev/null
  ;;
resume)
  port=$(cat "$dir/port")
  as_postgres "$bindir/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w \
    -o "-p $port -c listen_addresses=127.0.0.1 -k $dir -c max_connections=200 -c fsync=off" start >/dev/null
  ;;
stop)
  if [ -d "$dir/data" ]; then
    as_postgres "$bindir/pg_ctl" -D "$dir/data" -m fast -w stop >/dev/null || true
  fi
  rm -rf "$dir"
  ;;
*)
  echo "usage: $0 start|restart|crash|resume|stop DIR" >&2
  exit 2
  ;;
esac
