#!/usr/bin/env bash
# Proves the kernel tests can fail: applies each mutation in ci/mutants.txt (one per line:
# shader file | sed expression | test target), runs that test, and reports any mutation
# the tests did NOT catch (or those of the file given as $1). Restores every file. Not part of CI (it rebuilds per mutation).
set -uo pipefail
cd "$(dirname "$0")/.."
source ci/lavapipe.sh
survived=0
while read -r line; do
    [[ -z "$line" || "$line" == \#* ]] && continue
    # Fields are separated by " | " (spaces around the bar), so an expression may hold "||".
    file=${line%% | *}; rest=${line#* | }; test=${rest##* | }; expr=${rest% | *}
    cp "$file" /tmp/mutant.bak
    sed -i "$expr" "$file"
    if cmp -s "$file" /tmp/mutant.bak; then
        echo "NOT APPLIED  $file: $expr"; survived=1
    elif cargo test -q --test "$test" >/dev/null 2>&1; then
        echo "SURVIVED     $file: $expr ($test)"; survived=1
    else
        echo "caught       $file: $expr ($test)"
    fi
    cp /tmp/mutant.bak "$file"
done < "${1:-ci/mutants.txt}"
exit $survived
