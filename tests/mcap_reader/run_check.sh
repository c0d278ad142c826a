#!/usr/bin/env bash
# ctest "record: mcap ...": a 2 s default run with --record mcap, twice with
# the same seed; the two recording.mcap files must be byte-identical, and the
# reference TypeScript reader (check.mjs: @mcap/core, @foxglove/schemas) must
# accept the file. Without node or tests/mcap_reader/node_modules (scripts/setup
# installs them with npm ci) the test is SKIPPED (exit 77), never passed.
#
#   run_check.sh UAVSIM_CLI SCENARIO.json
set -euo pipefail
cli=$1 scenario=$2
here=$(cd "$(dirname "$0")" && pwd)
if ! command -v node >/dev/null; then
  echo "SKIPPED: no node on PATH (Debian nodejs: scripts/setup installs it)"
  exit 77
fi
if [[ ! -d $here/node_modules/@mcap/core || ! -d $here/node_modules/@foxglove/schemas ]]; then
  echo "SKIPPED: $here/node_modules lacks @mcap/core or @foxglove/schemas (scripts/setup runs npm ci there)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for k in a b; do
  "$cli" run "$scenario" --duration 2 --record mcap --quiet --out "$tmp/$k"
done
if ! cmp "$tmp/a/recording.mcap" "$tmp/b/recording.mcap"; then
  echo "FAILED: two runs of the same scenario and seed wrote different recording.mcap"
  exit 1
fi
node "$here/check.mjs" "$tmp/a"
