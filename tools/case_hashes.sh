#!/bin/sh
# The state hash of every shipped case after a short run, with both schemes: a change meant to alter structure only
# (not results) leaves this list identical. Usage: sh tools/case_hashes.sh [SURGE_BINARY] > hashes.txt
# Hashes compare within one build and machine kind (docs/architecture.md, "Threads and determinism").
set -e
cd "$(dirname "$0")/.."
surge=${1:-build/surge}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# case, explicit end time (s), implicit end time (s): a few hundred explicit steps and a few implicit ones
while read -r name t_explicit t_implicit; do
    for scheme in explicit implicit; do
        t=$t_explicit
        [ "$scheme" = implicit ] && t=$t_implicit
        hash=$("$surge" run "cases/$name.ini" -s numerics.scheme=$scheme -s time.end_s="$t" \
               -s output.snapshot_interval_s=0 -s output.progress_interval_s=0 -o "$out/$name-$scheme" --threads 2 2>&1 |
               sed -n 's/.*state hash \([0-9a-f]*\).*/\1/p')
        echo "$name $scheme $t ${hash:-failed}"
    done
done <<CASES
boulder_couette 0.05 0.5
boulder_settling 0.03 0.1
couette 0.1 1
debris_surge 0.1 1
belt_front 0.02 0.2
demo 0.02 0.2
freydier_id1 0.01 0.1
freydier_id2 0.005 0.05
incline_film 0.003 0.03
poiseuille 0.1 1
poiseuille_loaded 0.0002 0.002
still_tank 0.05 0.5
CASES
