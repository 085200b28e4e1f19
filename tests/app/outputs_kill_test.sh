#!/usr/bin/env bash
# A run's outputs are all or nothing: spacetime-cli runs are killed (SIGKILL) at random moments
# while they solve and write over a previous result, alternating two scenes; half of the kills
# fall in the write phase (within 60 ms of the new set's directory appearing). After every kill
# the output directory holds one complete set - the old or the new, never a mix - and no
# temporary; the temporaries a killed run left beside it are gone after the next run.
# Usage: outputs_kill_test.sh CLI SCENES_DIR LADDER_DIR [RUNS] (ctest: 12 runs; the issue's
# audit: 40).
set -u
cli="$1"
scenes="$2"
ladder="$3"
runs="${4:-12}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# A set's fingerprint: every file but the summary (whose timings vary), and the summary's objective.
signature() {
  [ -d "$1" ] || { echo missing; return; }
  local names
  names=$(cd "$1" && ls -A | tr '\n' ' ')
  [ "$names" = "luxo.bvh luxo.urdf motion.glb motion.json scene.json summary.json " ] || { echo "files: $names"; return; }
  (cd "$1" && cat luxo.bvh luxo.urdf motion.glb motion.json scene.json | md5sum | cut -d' ' -f1
   python3 -c 'import json, sys; print(json.load(open("summary.json"))["objective"])')
}

A="$scenes/luxo_jump.json"
B="$ladder/luxo_jump_0.3m.json"
"$cli" solve "$A" --out "$tmp/refA" --threads 1 --quiet 2>/dev/null || fail "scene A exited $?"
"$cli" solve "$B" --out "$tmp/refB" --threads 1 --quiet 2>/dev/null || fail "scene B exited $?"
sigA=$(signature "$tmp/refA")
sigB=$(signature "$tmp/refB")
[ "$sigA" != "$sigB" ] || fail "the two scenes give the same outputs"

cp -r "$tmp/refA" "$tmp/out"
changed=0
for i in $(seq 1 "$runs"); do
  if [ $((i % 2)) -eq 1 ]; then scene="$B"; else scene="$A"; fi
  before=$(signature "$tmp/out")
  "$cli" solve "$scene" --out "$tmp/out" --threads 1 --quiet 2>/dev/null &
  pid=$!
  if [ $((i % 4)) -lt 2 ]; then
    # Anywhere in the run: mostly while it solves.
    sleep "$(python3 -c "import random; print(round(random.uniform(0.2, 2.5), 3))")"
  else
    # In the write phase: within 60 ms of the new set's directory appearing beside --out.
    while [ ! -e "$tmp/.out.new-$pid" ] && kill -0 "$pid" 2>/dev/null; do sleep 0.002; done
    sleep "$(python3 -c "import random; print(round(random.uniform(0, 0.06), 4))")"
  fi
  kill -9 "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  after=$(signature "$tmp/out")
  [ "$after" = "$sigA" ] || [ "$after" = "$sigB" ] || fail "run $i left a mixed or incomplete set: $after"
  [ "$after" = "$before" ] || changed=$((changed + 1))
  ! ls -A "$tmp/out" | grep -q tmp || fail "run $i left a temporary inside the directory: $(ls -A "$tmp/out")"
done
echo "$runs runs killed at random moments: $changed replaced the set, $((runs - changed)) left the old one"

"$cli" solve "$A" --out "$tmp/out" --threads 1 --quiet 2>/dev/null || fail "the final run exited $?"
[ "$(signature "$tmp/out")" = "$sigA" ] || fail "the final run's set is wrong"
leftovers=$(ls -A "$tmp" | grep -v '^\(refA\|refB\|out\)$')
[ -z "$leftovers" ] || fail "temporaries survive the next run: $leftovers"
echo "1 passed, 0 failed"
