#!/usr/bin/env bash
# Proves the tests can fail: applies each mutation in ci/mutants.txt (one per line:
# file | sed expression | test target [test-name filter]; target "lib" = the unit tests),
# runs that test, and fails if a mutation survives or no longer applies.
# - Shader mutants are applied to a copy of shaders/ that RENDERNET_SHADER_DIR points at, so
#   they need no rebuild.
# - Rust mutants edit the file in place and rebuild. MUTANTS_RUST=all (default) runs every
#   one; =rotate runs one a day, in turn; =none skips them.
# - MUTANTS_BUDGET_S=S (CI sets it) stops starting mutants after S seconds, so CI's time is
#   bounded on a slow machine: mutants of files changed in the last MUTANTS_RECENT commits
#   (default 5) go first, then the rest from an offset that moves by a day's share each
#   day, so every mutant runs within a few days. Unset: every mutant, in file order.
#   Whatever the budget, every mutant is first checked to still apply.
# Usage: bash ci/mutants.sh [mutants file]. Every edited file is restored, even on Ctrl-C.
set -uo pipefail
cd "$(dirname "$0")/.."
source ci/lavapipe.sh
list=${1:-ci/mutants.txt}
mode=${MUTANTS_RUST:-all}
budget=${MUTANTS_BUDGET_S:-}
work=$(mktemp -d)
backup=""
restore() { [[ -n "$backup" ]] && cp "$work/original" "$backup"; rm -rf "$work"; }
trap restore EXIT
trap 'exit 130' INT TERM
cargo test -q --no-run 2>/dev/null || { echo "the tests do not build"; exit 1; }
mapfile -t lines < <(grep -v -e '^#' -e '^[[:space:]]*$' "$list")
rust_lines=$(printf '%s\n' "${lines[@]}" | grep -c '^src/')
today=$(( $(date +%s) / 86400 ))

# The order to run them in: every one in file order, or (with a budget) recent files first.
order=()
if [[ -z "$budget" ]]; then
    order=("${!lines[@]}")
else
    recent=$(git diff --name-only "HEAD~${MUTANTS_RECENT:-5}" 2>/dev/null || true)
    rest=()
    for i in "${!lines[@]}"; do
        if grep -qxF "${lines[i]%% | *}" <<<"$recent"; then order+=("$i"); else rest+=("$i"); fi
    done
    # About a fifth of the rest a day: the offset moves on by that much each day.
    n=${#rest[@]}
    if (( n > 0 )); then
        off=$(( (today * (n / 5 + 1)) % n ))
        order+=("${rest[@]:off}" "${rest[@]:0:off}")
    fi
fi

failed=0 caught=0 pos=0
# Every mutant must still apply, whether or not today's budget reaches it (a quick sed on a
# copy): an edit that moved a mutant's line fails CI the day it lands, not a later day.
stale=()
for i in "${!lines[@]}"; do
    line=${lines[i]}; file=${line%% | *}; rest=${line#* | }; expr=${rest% | *}
    cp "$file" "$work/check" && sed -i "$expr" "$work/check"
    if cmp -s "$work/check" "$file"; then echo "NOT APPLIED  $file: $expr"; failed=1; stale[i]=1; fi
done
start=$(date +%s)
for i in "${order[@]}"; do
    line=${lines[i]}
    [[ -n "${stale[i]:-}" ]] && continue
    if [[ -n "$budget" ]] && (( $(date +%s) - start >= budget )); then
        echo "budget of $budget s spent: $(( ${#order[@]} - pos )) of ${#order[@]} mutants left for other days"
        break
    fi
    pos=$((pos + 1))
    # Fields are separated by " | " (spaces around the bar), so an expression may hold "||".
    file=${line%% | *}; rest=${line#* | }; test=${rest##* | }; expr=${rest% | *}
    target=${test%% *}; filter=${test#"$target"}
    if [[ "$file" == shaders/* ]]; then
        rm -rf "$work/shaders"; cp -r shaders "$work/shaders"
        target_file="$work/$file"; original=$file; env=(RENDERNET_SHADER_DIR="$work/shaders")
    else
        # Rust mutants are numbered in file order, so `rotate` picks the same one whatever
        # the budget's order.
        rust_index=$(printf '%s\n' "${lines[@]:0:i}" | grep -c '^src/')
        [[ "$mode" == none ]] && continue
        [[ "$mode" == rotate && $(( rust_index != today % rust_lines )) == 1 ]] && continue
        cp "$file" "$work/original"; backup=$file
        target_file=$file; original="$work/original"; env=()
    fi
    # Target "lib": the library's own unit tests.
    if [[ "$target" == lib ]]; then sel=(--lib); else sel=(--test "$target"); fi
    t0=$(date +%s)
    sed -i "$expr" "$target_file"
    if cmp -s "$target_file" "$original"; then
        echo "NOT APPLIED  $file: $expr"; failed=1
    elif [[ -n "$backup" ]] && ! cargo test -q --no-run "${sel[@]}" >/dev/null 2>&1; then
        # A mutant that does not compile proves nothing about the tests.
        echo "NO BUILD     $file: $expr"; failed=1
    elif env "${env[@]}" cargo test -q "${sel[@]}" -- $filter >/dev/null 2>&1; then
        echo "SURVIVED     $file: $expr ($test)"; failed=1
    else
        echo "caught       $file: $expr ($test) $(( $(date +%s) - t0 )) s"; caught=$((caught + 1))
    fi
    if [[ -n "$backup" ]]; then cp "$work/original" "$backup"; backup=""; fi
done
echo "mutants: $caught caught of ${#lines[@]}, $(( $(date +%s) - start )) s; Rust mutants: $mode${budget:+; budget $budget s}"
exit $failed
