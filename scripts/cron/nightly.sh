#!/usr/bin/env bash
# Nightly conversion from cron (docs/cluster.md):
#   15 1 * * *  /opt/scanlod/scripts/cron/nightly.sh /srv/collections/museum.ini
# One instance per config on this host (flock on a lock file next to the config; a second
# start while the first still runs exits 75 at once -- overlapping runs on other hosts
# cooperate through the queues anyway). Old logs go by [run] log_keep. The exit code is
# scanlod's (docs/exit-codes.md), so cron mails a summary of non-zero runs.
set -uo pipefail
config=${1:?usage: nightly.sh CONFIG}
scanlod=${SCANLOD:-scanlod}
config_dir=$(cd "$(dirname "$config")" && pwd)
lock="$config_dir/.$(basename "$config").nightly.lock"
logs=${SCANLOD_LOGS:-$config_dir/logs}
mkdir -p "$logs"

exec 9>"$lock"
if ! flock -n 9; then
  echo "scanlod nightly: a run for $config is still going on this host; exiting 75" >&2
  exit 75
fi
"$scanlod" run "$config" -s "run.logs=$logs" -q
status=$?
[ "$status" -eq 0 ] || "$scanlod" status "$config" -s "run.logs=$logs"
exit "$status"
