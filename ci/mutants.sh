#!/usr/bin/env bash
# Proves the tests can fail: applies each mutation in ci/mutants.txt (one per line:
# file | sed expression | test target [test-name filter]; target "lib" = the unit tests),
# runs that test, and fails if a mutation survives or no longer applies.
# - Shader mutants are applied to a copy of shaders/ that RENDERNET_SHADER_DIR points at, so
#   they need no rebuild: all of them run every time.
# - Rust mutants edit the file in place and rebuild. MUTANTS_RUST=all (default) runs every
#   one (CI does); =rotate runs one a day, in turn; =none skips them.
# Usage: bash ci/mutants.sh [mutants file]. Every edited file is restored, even on Ctrl-C.
set -uo pipefail
cd "$(dirname "$0")/.."
source ci/lavapipe.sh
list=${1:-ci/mutants.txt}
mode=${MUTANTS_RUST:-all}
work=$(mktemp -d)
backup=""
restore() { [[ -n "$backup" ]] && cp "$work/original" "$backup"; rm -rf "$work"; }
trap restore EXIT
trap 'exit 130' INT TERM
cargo test -q --no-run 2>/dev/null || { echo "the tests do not build"; exit 1; }
rust_lines=$(grep -v '^#' "$list" | grep -c '^src/')
today=$(( $(date +%s) / 86400 ))
failed=0 caught=0 rust_seen=0
start=$(date +%s)
while read -r line; do
    [[ -z "$line" || "$line" == \#* ]] && continue
    # Fields are separated by " | " (spaces around the bar), so an expression may hold "||".
    file=${line%% | *}; rest=${line#* | }; test=${rest##* | }; expr=${rest% | *}
    target=${test%% *}; filter=${test#"$target"}
    if [[ "$file" == shaders/* ]]; then
        rm -rf "$work/shaders"; cp -r shaders "$work/shaders"
        target_file="$work/$file"; original=$file; env=(RENDERNET_SHADER_DIR="$work/shaders")
    else
        rust_seen=$((rust_seen + 1))
        [[ "$mode" == none ]] && continue
        [[ "$mode" == rotate && $(( (rust_seen - 1) != today % rust_lines )) == 1 ]] && continue
        cp "$file" "$work/original"; backup=$file
        target_file=$file; original="$work/original"; env=()
    fi
    # Target "lib": the library's own unit tests.
    if [[ "$target" == lib ]]; then sel=(--lib); else sel=(--test "$target"); fi
    sed -i "$expr" "$target_file"
    if cmp -s "$target_file" "$original"; then
        echo "NOT APPLIED  $file: $expr"; failed=1
    elif [[ -n "$backup" ]] && ! cargo test -q --no-run "${sel[@]}" >/dev/null 2>&1; then
        # A mutant that does not compile proves nothing about the tests.
        echo "NO BUILD     $file: $expr"; failed=1
    elif env "${env[@]}" cargo test -q "${sel[@]}" -- $filter >/dev/null 2>&1; then
        echo "SURVIVED     $file: $expr ($test)"; failed=1
    else
        echo "caught       $file: $expr ($test)"; caught=$((caught + 1))
    fi
    if [[ -n "$backup" ]]; then cp "$work/original" "$backup"; backup=""; fi
done < "$list"
echo "mutants: $caught caught, $(( $(date +%s) - start )) s; Rust mutants: $mode"
exit $failed
