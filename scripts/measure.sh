#!/usr/bin/env bash
# Re-measures every speed figure docs/performance.md and the README quote, on this machine, from
# the Release build: the solve and expression benchmarks (medians of 5 repetitions) and the jump
# ladder through spacetime-cli (single runs: the rungs take seconds to tens of seconds). Prints
# the tables in the documents' form. Takes about 12 minutes on the 2-core machine, plus the
# scaling rows (single solves, about 20 minutes for the two methods).
#
#   scripts/measure.sh            everything
#   scripts/measure.sh benchmarks the benchmarks only
#   scripts/measure.sh methods    the methods tables only (al, sqp, witkin-kass; about 20 minutes;
#                                 METHODS="sqp" scripts/measure.sh methods: the sqp rows only)
#   scripts/measure.sh characters the methods on the biped, the quadruped and the humanoid only
#   scripts/measure.sh editor     the editor's own solves under Xvfb only (about 3 minutes)
#   scripts/measure.sh speedlimits the jump under joint speed limits only (about 10 minutes)
#   scripts/measure.sh motionstarts solves started from a motion.json alone only (about 2 minutes)
#   scripts/measure.sh scaling    the scaling rows only, by the scene's method and by sqp (about
#                                 20 minutes)
#   scripts/measure.sh secondorder the second-order check of every shipped scene's optimum, and of
#                                 each method's on the hurdle and the 0.3 m rung (about 3 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --build build -j2 --target solve_benchmark expr_benchmark editor_benchmark spacetime-cli spacetime > /dev/null
bench=build/tests/benchmarks
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The Scaling rows (the scene's method, `al`) and the ScalingSqp rows (the same scenes by `sqp`),
# each with the least-squares exponents of time, steps and time per step over its valid rows.
scaling_tables() {
  for rows in Scaling ScalingSqp; do
    echo
    echo "## $rows (solve_benchmark's $rows rows, 2 threads, single runs)"
    echo
    "$bench/solve_benchmark" --benchmark_filter="BM_$rows/" --benchmark_format=json \
      --benchmark_out="$tmp/$rows.json" --benchmark_out_format=json > /dev/null
    python3 - "$tmp/$rows.json" "$rows" <<'PY'
import json, math, sys
rows = [b for b in json.load(open(sys.argv[1]))["benchmarks"] if b.get("run_type") == "iteration"]
sqp = sys.argv[2] == "ScalingSqp"
def steps(b):  # the method's own steps: the SQP's, or the augmented Lagrangian's LM iterations
    return b.get("sqp_steps", 0) if sqp else b["lm_iterations"]
def per_step(b):
    return b.get("sqp_ms_per_step", 0) if sqp else b.get("lm_ms_per_iteration", 0)
kind = "SQP steps" if sqp else "LM iterations"
after = " LM iterations after a hand-over |" if sqp else ""  # sqp's hand-overs to al
print(f"| scene | clip | dofs | time | {kind} + Newton steps | ms per {kind[:-1]} |{after} transcriptions | objective | valid |")
print("|---" * (10 if sqp else 9) + "|")
for b in rows:
    name = b["run_name"].split("/")[1]
    s = b["real_time"] / 1e3
    lm = f" {b['lm_iterations']:.0f} |" if sqp else ""
    print(f"| {name} | {b['clip_seconds']:.1f} s | {b['dofs']:.0f} | {s:.3g} s | {steps(b):.0f} + {b['newton_steps']:.0f} | "
          f"{per_step(b):.2f} |{lm} {b['transcriptions']:.0f} | {b['objective']:.4f} | {'yes' if b['valid'] else 'no'} |")
def slope(points):  # least-squares exponent of y = c x^a
    xs = [math.log(x) for x, _ in points]; ys = [math.log(y) for _, y in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
for family, key in (("hops", "clip_seconds"), ("chain", "dofs")):
    sel = [b for b in rows if f"/{family}_" in b["run_name"] and b["valid"]]
    if len(sel) < 2:
        continue
    t = slope([(b[key], b["real_time"]) for b in sel])
    its = slope([(b[key], steps(b)) for b in sel])
    line = f"\n{family} (valid rows): time ~ {key}^{t:.2f}, {kind} ~ {key}^{its:.2f}"
    if all(per_step(b) > 0 for b in sel):
        line += f", ms per {kind[:-1]} ~ {key}^{slope([(b[key], per_step(b)) for b in sel]):.2f}"
    print(line)
PY
  done
}
[ "${1:-}" = scaling ] && { scaling_tables; exit 0; }

# The methods side by side: every shipped scene, then the ladder's required rungs (al's own
# figures are in the ladder table above).
methods_tables() {
  echo
  echo "## The methods on the shipped scenes (spacetime-cli solve --method M, 2 threads, single runs)"
  echo
  echo "| scene | method | exit | objective | SQP or projected steps (s in programs) | LM iterations + Newton passes | seconds |"
  echo "|---|---|---|---|---|---|---|"
  for name in particle particle_gravity luxo_jump luxo_hurdle luxo_heavy luxo_3d luxo_power_formula; do
    for method in $(chosen al sqp witkin-kass); do
      method_row "resources/scenes/$name.json" "$name" "$method"
    done
  done
  echo
  echo "## The ladder's required rungs by method (spacetime-cli solve --method M, 2 threads, single runs)"
  echo
  echo "| scene | method | exit | objective | SQP or projected steps (s in programs) | LM iterations + Newton passes | seconds |"
  echo "|---|---|---|---|---|---|---|"
  for name in luxo_hurdle_double luxo_jump_0.3m luxo_jump_0.6m luxo_jump_0.9m luxo_jump_1.2m luxo_jump_1.5m; do
    for method in $(chosen sqp witkin-kass); do
      method_row "tests/scenes/ladder/$name.json" "$name" "$method"
    done
  done
  characters_table
}
characters_table() {
  echo
  echo "## The methods beyond the lamps (spacetime-cli solve --method M, 2 threads, single runs)"
  echo
  echo "| scene | method | exit | objective | SQP or projected steps (s in programs) | LM iterations + Newton passes | seconds |"
  echo "|---|---|---|---|---|---|---|"
  for name in biped_jump quadruped_hop humanoid_jump; do
    for method in $(chosen al sqp witkin-kass); do
      method_row "resources/scenes/$name.json" "$name" "$method"
    done
  done
}
# The methods given, less those METHODS (when set) leaves out.
chosen() {
  local m
  for m in "$@"; do
    [[ -z "${METHODS:-}" || " $METHODS " == *" $m "* ]] && echo "$m"
  done
  return 0
}
method_row() {
  set +e
  build/app/spacetime-cli solve "$1" --out "$tmp/m_$2_$3" --method "$3" --quiet --max-seconds 300 2> /dev/null
  local status=$?
  set -e
  python3 - "$tmp/m_$2_$3/summary.json" "$2" "$3" "$status" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
total = sum(a["seconds"] for a in s.get("refinement", [])) or s["solve_seconds"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {s['objective']:.6f} | {s['sqp_steps']} ({s['qp_seconds']:.2f}) | "
      f"{s['iterations']} + {s['newton_steps']} | {total:.2f} |")
PY
}
[ "${1:-}" = methods ] && { methods_tables; exit 0; }
[ "${1:-}" = characters ] && { characters_table; exit 0; }

# The editor solving with its window shown and drawing iterates (spacetime --screenshot under
# Xvfb, Mesa llvmpipe; single runs): the README's and docs/design.md's editor solve times.
editor_solves() {
  echo
  echo "## The editor's solves (spacetime --screenshot under Xvfb, window shown, single runs)"
  echo
  echo "| scene | solve | objective | wall time of the run |"
  echo "|---|---|---|---|"
  python3 -c 'import json, sys; s = json.load(open(sys.argv[1])); s["transcription"]["samplesPerSegment"] = 3; json.dump(s, open(sys.argv[2], "w"))' \
    resources/scenes/luxo_jump.json "$tmp/luxo_jump_s3.json"
  for scene in "$tmp/luxo_jump_s3.json" tests/scenes/ladder/luxo_jump_1.2m.json; do
    local start end line
    start=$(date +%s.%N)
    line=$(xvfb-run -a -s "-screen 0 1600x1000x24" build/app/spacetime --screenshot "$tmp/shot.png" "$scene" 2>&1 | grep "wrote" || true)
    end=$(date +%s.%N)
    echo "| $(basename "$scene" .json) | $(echo "$line" | grep -o '[A-Z][a-z]* after [0-9]* iterations ([0-9.]* s)') | $(echo "$line" | grep -o 'objective [0-9.]*' | cut -d' ' -f2) | $(python3 -c "print(f'{$end - $start:.1f} s')") |"
  done
}
[ "${1:-}" = editor ] && { editor_solves; exit 0; }

# Solves started from a motion.json alone (spacetime-cli --init, no scene.json beside it): each
# scene solved cold, its motion.json (at RATE frames per second) moved away, the scene solved
# again from it - by sqp, as the CLI chooses for a scene whose method is al, and by al and
# witkin-kass when asked (from the multipliers the CLI estimates for them).
motion_starts() {
  echo
  echo "## Solves from a motion file alone (spacetime-cli solve SCENE --init motion.json, 2 threads, single runs)"
  echo
  echo "| scene | motion's frames per second | method | SQP steps + Newton steps | LM iterations | objective | cold objective | seconds |"
  echo "|---|---|---|---|---|---|---|---|"
  local name rate method
  for run in luxo_jump:1000:auto luxo_jump:120:auto luxo_jump:60:auto luxo_jump:24:auto luxo_jump:1000:al \
             luxo_jump:120:al luxo_jump:1000:witkin-kass luxo_hurdle:1000:auto luxo_hurdle:1000:al \
             luxo_3d:1000:auto luxo_3d:1000:al biped_jump:1000:auto biped_jump:1000:al; do
    IFS=: read -r name rate method <<< "$run"
    [ -d "$tmp/cold_$name" ] || build/app/spacetime-cli solve "resources/scenes/$name.json" --out "$tmp/cold_$name" --quiet --max-seconds 300 2> /dev/null || true
    rm -rf "$tmp/rated" "$tmp/lone" "$tmp/from_motion"
    build/app/spacetime-cli solve "$tmp/cold_$name/scene.json" --out "$tmp/rated" --quiet --rate "$rate" 2> /dev/null || true
    mkdir -p "$tmp/lone" && cp "$tmp/rated/motion.json" "$tmp/lone/"
    local extra=()
    [ "$method" = auto ] || extra=(--method "$method")
    build/app/spacetime-cli solve "resources/scenes/$name.json" --out "$tmp/from_motion" --init "$tmp/lone/motion.json" \
      "${extra[@]}" --quiet --max-seconds 300 2> /dev/null || true
    python3 - "$tmp/from_motion/summary.json" "$tmp/cold_$name/summary.json" "$name" "$rate" <<'PY'
import json, sys
s, cold = (json.load(open(p)) for p in sys.argv[1:3])
print(f"| {sys.argv[3]} | {sys.argv[4]} | {s['method']} | {s['sqp_steps']} + {s['newton_steps']} | {s['iterations']} | "
      f"{s['objective']:.6f} | {cold['objective']:.6f} | {s['solve_seconds']:.2f} |")
PY
  done
}
[ "${1:-}" = motionstarts ] && { motion_starts; exit 0; }

# The shipped jump with a speed limit on every joint (docs/validation.md, "Not yet holding"):
# 30 rad/s from the default guess, then the limit stepped down, each step from the last step's
# scene.json with only speedLimit changed (its own transcription, restored exactly).
speed_limits() {
  echo
  echo "## The jump under joint speed limits (spacetime-cli solve, 2 threads, single runs)"
  echo
  echo "| limit (rad/s) | start | exit | objective | largest violation | transcription | seconds |"
  echo "|---|---|---|---|---|---|---|"
  local from="resources/scenes/luxo_jump.json" start="default guess" options=""
  for limit in 30 27.5 25; do
    python3 -c 'import json, sys
s = json.load(open(sys.argv[1]))
for b in s["characters"][0]["bodies"]:
    if "joint" in b: b["joint"]["speedLimit"] = float(sys.argv[2])
json.dump(s, open(sys.argv[3], "w"))' "$from" "$limit" "$tmp/speed_$limit.json"
    set +e
    # shellcheck disable=SC2086
    build/app/spacetime-cli solve "$tmp/speed_$limit.json" --out "$tmp/speed_$limit" --quiet --max-seconds 300 $options 2> /dev/null
    local status=$?
    set -e
    python3 - "$tmp/speed_$limit/summary.json" "$limit" "$start" "$status" "$tmp/speed_$limit/scene.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
t = json.load(open(sys.argv[5]))["transcription"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {s['objective']:.6f} | {s['max_violation']:.3g} | "
      f"{t['controlPointsPerSecond']:g} / {t['samplesPerSegment']} | {s['solve_seconds']:.0f} |")
PY
    from="$tmp/speed_$limit/scene.json" start="$limit rad/s" options="--max-refinements 0"
  done
}
[ "${1:-}" = speedlimits ] && { speed_limits; exit 0; }
# The second-order check (--second-order) of the optima README.md and docs/design.md quote.
second_order() {
  echo
  echo "## The second-order check (spacetime-cli solve --second-order, 2 threads, single runs)"
  echo
  echo "| scene | method | objective | verdict | smallest eigenvalue | free directions | active (dependent) | stationarity | check seconds | along |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  local runs="" name
  for name in particle luxo_jump luxo_hurdle luxo_heavy luxo_3d luxo_power_formula biped_jump quadruped_hop humanoid_jump; do
    runs="$runs resources/scenes/$name.json:al"
  done
  runs="$runs resources/scenes/luxo_hurdle.json:sqp tests/scenes/ladder/luxo_hurdle_double.json:al"
  for method in al sqp witkin-kass; do runs="$runs tests/scenes/ladder/luxo_jump_0.3m.json:$method"; done
  runs="$runs tests/scenes/ladder/luxo_jump_0.9m.json:al"
  local run scene method out
  for run in $runs; do
    scene=${run%%:*} method=${run##*:} out="$tmp/second_order_$(basename "$scene" .json)_$method"
    build/app/spacetime-cli solve "$scene" --out "$out" --method "$method" --quiet --second-order 2> /dev/null || true
    python3 - "$out/summary.json" "$(basename "$scene" .json)" "$method" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
c = s.get("second_order", {})
if not c.get("checked"):
    print(f"| {sys.argv[2]} | {sys.argv[3]} | {s['objective']:.6f} | {c.get('reason', 'not run')} | | | | | | |")
    sys.exit()
verdict = ("strict minimum" if c["strict_minimum"] else
           f"strict motion, {c['free_force_directions']} free force directions" if c["strict_motion"] else
           "saddle" if "saddle" in c["reason"] else "not shown" if c["smallest_eigenvalue"] < -c["rounding_floor"] else "flat")
print(f"| {sys.argv[2]} | {sys.argv[3]} | {s['objective']:.6f} | {verdict} | {c['smallest_eigenvalue']:.3g} | {c['free_directions']} | "
      f"{c['active_constraints']} ({c['dependent_constraints']}) | {c['stationarity']:.2g} | {c['seconds']:.3f} | {'; '.join(c['direction'][:2])} |")
PY
  done
}
[ "${1:-}" = secondorder ] && { second_order; exit 0; }

echo "## Solves from the default guess (solve_benchmark, medians of 5)"
echo
"$bench/solve_benchmark" --benchmark_filter=-Scaling --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_format=json --benchmark_out="$tmp/solve.json" --benchmark_out_format=json > /dev/null
python3 - "$tmp/solve.json" <<'PY'
import json, sys
rows = [b for b in json.load(open(sys.argv[1]))["benchmarks"] if b.get("aggregate_name") == "median"]
print("| benchmark | median | LM iterations + Newton steps | ms per LM iteration (evaluation, linear solver) | ms per Newton step (Hessian, factorisation, line search) | converged |")
print("|---|---|---|---|---|---|")
for b in rows:
    name = b["run_name"].replace("BM_", "").replace("/iterations:1", "").replace("/real_time", "")
    t = b["real_time"]
    unit = b["time_unit"]
    ms = t / 1e6 if unit == "ns" else t / 1e3 if unit == "us" else t if unit == "ms" else t * 1e3
    when = f"{ms:.3g} ms" if ms < 1000 else f"{ms / 1000:.3g} s"
    steps = ""
    if "sqp_steps" in b:  # the SQP: its steps, their time and their programs' part
        steps = (f"{b['sqp_steps']:.0f} SQP steps, {b['sqp_ms_per_step']:.0f} ms each ({b['sqp_program_ms']:.0f} in programs), "
                 f"then {b['lm_iterations']:.0f} + {b.get('newton_steps', 0):.0f}")
    elif "lm_iterations" in b:
        steps = f"{b['lm_iterations']:.0f} + {b.get('newton_steps', 0):.0f}"
    elif "qp_iterations" in b:  # one quadratic program: its interior-point iterations and their cost
        steps = (f"{b['qp_iterations']:.0f} interior-point iterations, {ms / max(1, b['qp_iterations']):.2f} ms each "
                 f"({b['variables']:.0f} variables, {b['equalities']:.0f} equalities, {b['inequalities']:.0f} inequalities)")
    elif "ip_iterations" in b:  # the interior point (IPOPT): its iterations and their cost
        steps = f"{b['ip_iterations']:.0f} IPOPT iterations"
        if b.get("ip_ms_per_iteration"):
            steps += f", {b['ip_ms_per_iteration']:.1f} ms each (evaluation {100 * b['ip_evaluation_share']:.0f} %, Hessian {100 * b['ip_hessian_share']:.0f} %)"
    elif "rows" in b:
        steps = f"{b['rows']:.0f} rows x {b['cols']:.0f} columns"
    elif "residuals" in b:  # a problem's build
        steps = f"{b['residuals']:.0f} residual blocks"
    conv = {1: "yes", 0: "no"}.get(b.get("converged", b.get("valid")), "")
    lm = newton = ""
    if b.get("lm_ms_per_iteration"):
        lm = f"{b['lm_ms_per_iteration']:.2f} ({100 * b['lm_evaluation_share']:.0f} %, {100 * b['lm_linear_solver_share']:.0f} %)"
    if b.get("newton_ms_per_step"):
        newton = f"{b['newton_ms_per_step']:.1f}"
        if "newton_hessian_ms" in b:
            newton += f" ({b['newton_hessian_ms']:.1f}, {b['newton_factorisation_ms']:.1f}, {b['newton_line_search_ms']:.1f})"
    if b.get("chord_steps"):  # a warm polish's steps on the factorisation kept from the last optimum
        steps += f" ({b['chord_steps']:.0f} on the kept factorisation)"
    if "transcriptions" in b:
        steps += f", {b['transcriptions']:.0f} transcription(s)"
    print(f"| {name} | {when} | {steps} | {lm} | {newton} | {conv} |")
PY
echo
echo "## Expression tape vs native RNEA (expr_benchmark, medians of 5)"
echo
"$bench/expr_benchmark" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_format=json --benchmark_out="$tmp/expr.json" --benchmark_out_format=json > /dev/null
python3 - "$tmp/expr.json" <<'PY'
import json, sys
rows = {b["run_name"]: b for b in json.load(open(sys.argv[1]))["benchmarks"] if b.get("aggregate_name") == "median"}
def ns(b):
    return b["real_time"] * {"ns": 1, "us": 1e3, "ms": 1e6}[b["time_unit"]]
tape, native = ns(rows["BM_SymbolicRneaTape"]), ns(rows["BM_NativeRnea"])
print("| figure | median |")
print("|---|---|")
print(f"| planar lamp's RNEA as a compiled tape | {tape:.0f} ns |")
print(f"| the same RNEA, native templated code | {native:.0f} ns |")
print(f"| tape / native | {tape / native:.2f}x |")
print(f"| TapeEvaluate | {ns(rows['BM_TapeEvaluate']) / 1e3:.2f} us |")
PY
echo
echo "## The editor (editor_benchmark under Xvfb, Mesa llvmpipe, medians of 5)"
echo
xvfb-run -a -s "-screen 0 1600x1000x24" "$bench/editor_benchmark" --benchmark_repetitions=5 \
  --benchmark_report_aggregates_only=true --benchmark_format=json --benchmark_out="$tmp/editor.json" \
  --benchmark_out_format=json > /dev/null 2>&1
python3 - "$tmp/editor.json" <<'PY'
import json, sys
print("| benchmark | median |")
print("|---|---|")
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b.get("aggregate_name") != "median":
        continue
    name = b["run_name"].replace("BM_", "").split("/iterations")[0].replace("/manual_time", "")
    ms = b["real_time"] * {"ns": 1e-6, "us": 1e-3, "ms": 1, "s": 1e3}[b["time_unit"]]
    if "gap_ms" in b:  # the figure is the longest gap, not the run's length
        print(f"| {name}: longest event-loop gap | {b['gap_ms']:.3g} ms |")
    else:
        print(f"| {name} | {ms:.3g} ms |")
PY
[ "${1:-}" = benchmarks ] && exit 0
editor_solves
speed_limits

scaling_tables

echo
echo "## The jump ladder (spacetime-cli solve, 2 threads, single runs)"
echo
echo "| scene | exit | objective | transcriptions tried | seconds |"
echo "|---|---|---|---|---|"
for scene in tests/scenes/ladder/*.json; do
  name=$(basename "$scene" .json)
  set +e
  build/app/spacetime-cli solve "$scene" --out "$tmp/$name" --quiet --max-seconds 120 2> /dev/null
  status=$?
  set -e
  python3 - "$tmp/$name/summary.json" "$name" "$status" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
tried = ", ".join(f"{a['control_points_per_second']:g}/{a['samples_per_segment']}" for a in s.get("refinement", [])) or "the scene's"
total = sum(a["seconds"] for a in s.get("refinement", [])) or s["solve_seconds"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {s['objective']:.6g} | {tried} | {total:.1f} |")
PY
done

methods_tables
motion_starts
second_order
