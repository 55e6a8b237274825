#!/usr/bin/env bash
# The GPU machine's whole job, in one call of the device tool (carry [".deps"], made on the build
# machine by Utilities/gpu/deps.sh):
#   1. build Solver/ alone with CUDA for sm_90 (no ParaView there), all cores
#   2. ctest, labels gpu and solver
#   3. compute-sanitizer memcheck and racecheck on small scenes (must report 0 errors)
#   4. pbf_bench: the CUDA sweep 16k-16M in single precision, 10M and 100M, double precision,
#      the cell walk, skins, graphs off, and the serial and OpenMP references on this CPU
#   5. the surface: GPU against this machine's CPU cores on the 1.15M and 9.2M dam breaks
#   6. ncu: per-kernel times of one step at 1M, and the neighbour passes' sections
# PBF_GPU_SKIP_BENCH=1, PBF_GPU_SKIP_CTEST=1, PBF_GPU_SKIP_SURFACE=1, PBF_GPU_SKIP_SANITIZERS=1
# leave phases out; PBF_GPU_CTEST_FILTER=REGEX runs only the matching tests; PBF_GPU_PAIR_PROBE=1
# adds Utilities/gpu/pair_once_probe.cu (the neighbour passes' structures, apart from the solver).
# Logs and JSON go under $OUT (else output/gpu-run); a short table is printed last. Every phase
# has a time limit inside a budget of PBF_GPU_BUDGET seconds (default 540), so the table comes
# within the device tool's 10 minutes whatever happens.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${OUT:-$root/output/gpu-run}
build=${PBF_GPU_BUILD:-/tmp/pbf-gpu-build}
work=/tmp/pbf-gpu-run
budget=${PBF_GPU_BUDGET:-540}
mkdir -p "$out" "$work"
rm -f "$work"/*.json
exec > >(tee "$out/run.log") 2>&1
t0=$SECONDS
results=()
phase() { echo; echo "== [$((SECONDS - t0)) s] $*"; }
# limit SECONDS: the phase's own limit, cut to what the budget has left (30 s kept for the end).
limit() {
  local left=$((budget - 30 - (SECONDS - t0)))
  ((left < $1)) && echo $((left > 5 ? left : 5)) || echo "$1"
}
record() { results+=("$1"); echo ">> $1"; }

phase "machine"
nvidia-smi --query-gpu=name,driver_version,memory.total,memory.used,clocks.sm,clocks.max.sm,power.limit \
  --format=csv 2>&1 || true
echo "cores: $(nproc); $(nvcc --version | tail -1); $(cmake --version | head -1)"
command -v compute-sanitizer ncu ninja || true

phase "build"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if timeout "$(limit 300)" cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DPBF_SOLVER_ONLY=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" -DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest" \
    >"$work/configure.log" 2>&1 &&
  timeout "$(limit 300)" cmake --build "$build" -j "$(nproc)" >"$work/build.log" 2>&1; then
  record "build: ok ($((SECONDS - t0)) s)"
else
  tail -n 40 "$work/configure.log" "$work/build.log"
  record "build: FAILED"
  exit 1
fi
grep -E "warning|spill" "$work/build.log" | grep -v "^--" | head -20
# The neighbour passes' machine code, for reading offline.
for object in "$build"/Solver/CMakeFiles/pbf_solver.dir/Cuda/CudaFloat.cu.o; do
  cuobjdump -sass "$object" 2>/dev/null | gzip >"$work/float.sass.gz" || true
done
bench=$build/Solver/Tools/pbf_bench
run=$build/Solver/Tools/pbf_run

# bench NAME SECONDS ARGS...: one pbf_bench run, its JSON kept for the table.
bench() {
  local name=$1 seconds=$2
  shift 2
  phase "bench $name: $*"
  timeout "$(limit "$seconds")" "$bench" "$@" --json "$work/$name.json" --label "$name" ||
    record "bench $name: FAILED or cut (exit $?)"
}

# PBF_GPU_QUICK=1: a verification run after a change (tests, sanitizers, soak, 1M and 10M
# timings); the full sweeps and ncu are for when the speed itself is the question.
quick=${PBF_GPU_QUICK:-0}
if [[ ${PBF_GPU_SKIP_BENCH:-0} == 1 ]]; then
  phase "bench: skipped (PBF_GPU_SKIP_BENCH=1)"
elif ((quick)); then
  bench cuda_single 60 --backend cuda --sweep 64000,1000000 --warmup 20 --steps 100
  bench cuda_double 40 --backend cuda --precision double --particles 1000000 --warmup 20 --steps 100
  bench cuda_10M 40 --backend cuda --particles 10000000 --warmup 10 --steps 50
  # What an obstacle costs at 1M: a sphere, and the MARIN box (the bound: 15 %).
  bench cuda_sphere 30 --backend cuda --particles 1000000 --warmup 20 --steps 100 --solid 1
  bench cuda_box 30 --backend cuda --particles 1000000 --warmup 20 --steps 100 --solid 2
  bench cuda_rolling 30 --backend cuda --particles 1000000 --warmup 20 --steps 100 --solid 3
  # No particle inside an obstacle, on one GPU and decomposed over two (on this one GPU).
  for ranks in 1 2; do
    phase "obstacle check, $ranks rank(s)"
    timeout "$(limit 120)" "$build/Solver/Tools/pbf_obstacle_check" --backend cuda \
      --spacing 0.02 --ranks "$ranks" >"$work/obstacles_$ranks.txt" 2>&1
    cat "$work/obstacles_$ranks.txt"
    record "obstacles, $ranks rank(s): $(tail -n +2 "$work/obstacles_$ranks.txt" | cut -d, -f1,5-9 | tr '\n' ' ')"
  done
else
bench cuda_single 120 --backend cuda --sweep default --warmup 20 --steps 100
bench cuda_10M 40 --backend cuda --particles 10000000 --warmup 10 --steps 50
bench cuda_100M 90 --backend cuda --particles 100000000 --warmup 3 --steps 10
bench cuda_double 60 --backend cuda --precision double --sweep 16000,64000,256000,1000000,4000000 \
  --warmup 20 --steps 100
bench cuda_walk 60 --backend cuda --neighbors walk --sweep 64000,256000,1000000,4000000 --warmup 20 \
  --steps 50
for skin in 0.02 0.1; do
  bench "cuda_skin_$skin" 20 --backend cuda --skin "$skin" --particles 1000000 --warmup 20 --steps 100
done
# What the mirror walls (Equations.h) cost: the same run without them.
bench cuda_nowalls 20 --backend cuda --walls 0 --particles 1000000 --warmup 20 --steps 100
bench cuda_nographs 30 --backend cuda --graphs 0 --sweep 16000,64000,1000000 --warmup 20 --steps 100
bench serial 90 --backend serial --sweep 16000,64000,256000 --warmup 1 --steps 3
bench serial_1M 40 --backend serial --particles 1000000 --warmup 0 --steps 1
bench openmp 40 --backend openmp --sweep 64000,256000,1000000 --warmup 1 --steps 3
fi

if [[ ${PBF_GPU_SKIP_CTEST:-0} == 1 ]]; then
  phase "ctest: skipped (PBF_GPU_SKIP_CTEST=1)"
else
phase "ctest (gpu, solver)"
# Here a GPU must be: a GPU test that finds none fails instead of reporting SKIPPED
# (Testing/Cuda/RequireGpu.h). The two tests of the behaviour without a GPU still skip.
export PBF_GPU_REQUIRED=1
# PBF_GPU_CTEST_FILTER=REGEX: only the tests whose names match (ctest -R).
filter=()
[[ -n ${PBF_GPU_CTEST_FILTER:-} ]] && filter=(-R "$PBF_GPU_CTEST_FILTER")
(cd "$build" && timeout "$(limit 240)" ctest -L 'gpu|solver' "${filter[@]}" -j "$(nproc)" --timeout 300 \
  --output-on-failure) >"$work/ctest.log" 2>&1
ctest_status=$?
grep -E "tests passed|Skipped|Failed|\*\*\*|Timeout|Exception|CMake Error" "$work/ctest.log" | head -60
record "ctest gpu|solver: $(grep -E 'tests passed' "$work/ctest.log" | tail -1) (exit $ctest_status)"
if grep -q "CMake Error" "$work/ctest.log"; then
  # CTest could not read a generated test list: run the test programs themselves.
  for program in Testing/Cuda/pbf_cuda_tests Testing/Cuda/pbf_cuda_schedule_tests \
    Testing/Solver/pbf_solver_tests; do
    timeout "$(limit 200)" "$build/$program" >"$work/$(basename "$program").log" 2>&1
    record "$(basename "$program"): $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' "$work/$(basename "$program").log" | tr '\n' ' ')"
  done
fi

fi

if [[ ${PBF_GPU_SKIP_SURFACE:-0} == 1 ]]; then
  phase "surface: skipped (PBF_GPU_SKIP_SURFACE=1)"
else
  # The GPU surface against the CPU's on this machine's cores, the same frame in one run
  # (Documentation/Performance.md): the 1.15M dam break at t = 0.2 s and the 9.2M at 0.05 s.
  surface_run() { # surface_run NAME SECONDS ARGS...
    local name=$1 seconds=$2
    shift 2
    phase "surface $name: $*"
    timeout "$(limit "$seconds")" "$build/Solver/Tools/pbf_surface" --backend cuda --scene dam_break "$@" \
      >"$work/surface_$name.txt" 2>&1
    local status=$?
    cat "$work/surface_$name.txt"
    record "surface $name: $(tail -n 1 "$work/surface_$name.txt") (exit $status)"
  }
  surface_run 1M 90 --spacing 0.005 --until 0.2 --cpu-repeat 3
  surface_run 9M 120 --spacing 0.0025 --until 0.05 --cpu-repeat 1 --repeat 5
  surface_run 1M_anisotropic 90 --spacing 0.005 --until 0.2 --cpu-repeat 1 --anisotropic 1
  if [[ ${PBF_GPU_SURFACE_PROFILE:-0} == 1 ]]; then
    # Per-kernel device times of the surface's own kernels at 1.15M (ncu, over the three
    # extractions pbf_surface makes with --repeat 1; CUB's sorts, scans and selections are the
    # rest of the extraction's time: the stepper runs CUB's kernels too, so they are left out).
    phase "ncu: the surface's kernels"
    timeout "$(limit 150)" ncu --clock-control none --metrics gpu__time_duration.sum --csv --page raw \
      --kernel-name-base function \
      -k 'regex:(sampleBlocks|countCells|placeVertices|cutCells|vertexFields|markBlocks|cellOffsets|axisKeys|cellKeys|gatherKeys|gatherPositions|gatherShapes|firstNonFinite|anisotropy|smooth|directedEdges|edgeOffsets)Kernel' \
      "$build/Solver/Tools/pbf_surface" --backend cuda --scene dam_break --spacing 0.005 --until 0.2 \
      --cpu-repeat 1 --repeat 1 >"$out/ncu_surface.csv" 2>&1 || record "ncu surface: FAILED or cut"
    python3 - "$out/ncu_surface.csv" <<'PY' || true
import csv, collections, sys
rows = [r for r in csv.reader(open(sys.argv[1])) if len(r) > 10]
rows = rows[[i for i, r in enumerate(rows) if "Kernel Name" in r][0]:]  # pbf_surface's own lines first
head = rows[0]
name, value = head.index("Kernel Name"), head.index("gpu__time_duration.sum")
total = collections.Counter()
for r in rows[2:]:
    try:
        total[r[name].split("(")[0]] += float(r[value].replace(",", "")) / 3e3  # ns -> us per extraction
    except ValueError:
        pass
for kernel, us in total.most_common(20):
    print("%-40s %9.1f us per extraction" % (kernel, us))
print("%-40s %9.1f us" % ("sum", sum(total.values())))
PY
  fi
fi

if [[ ${PBF_GPU_SKIP_SANITIZERS:-0} == 1 ]]; then
  phase "compute-sanitizer and soak: skipped (PBF_GPU_SKIP_SANITIZERS=1)"
else
phase "compute-sanitizer"
# sanitize "TOOL [OPTIONS]" PROGRAM ARGS...
sanitize() {
  local tool=($1)
  shift
  local log="$work/sanitizer-${tool[0]}-$RANDOM.log"
  # racecheck (2025.3.1) dies with SIGSEGV on a CUDA graph with conditional nodes, which the
  # adaptive projections use: it checks the same kernels launched one by one.
  local graphs=1
  [[ ${tool[0]} == racecheck ]] && graphs=0
  PBF_CUDA_GRAPHS=$graphs timeout "$(limit 90)" compute-sanitizer --tool "${tool[@]}" \
    --error-exitcode 9 "$@" >"$log" 2>&1
  local status=$?
  tail -n 3 "$log"
  record "${tool[0]} $(basename "$1") ${*:2}: $(grep -E 'ERROR SUMMARY|RACECHECK SUMMARY' "$log" | tail -1) (exit $status)"
}
small=(--backend cuda --particles 4000 --warmup 2 --steps 3)
sanitize "memcheck --leak-check full" "$bench" "${small[@]}"
sanitize memcheck "$bench" "${small[@]}" --precision double --neighbors walk --graphs 0
sanitize memcheck "$run" --backend cuda --scene stream --spacing 0.01 --steps 20 --report 10
sanitize racecheck "$bench" "${small[@]}"
# The adaptive projections' reductions (shared memory) on the refined dam break's defaults.
sanitize racecheck "$bench" --backend cuda --refined 0.05 --until 0.05 --modes defaults
# The GPU surface's tests (host and device arrays, obstacles, smoothing).
for tool in memcheck initcheck; do
  sanitize "$tool" "$build/Testing/Cuda/pbf_cuda_tests" --gtest_filter='CudaSurface.*'
done
# The outflows' removal (a selection, gathers, the step captured again) on one GPU and on ranks.
sanitize memcheck "$build/Testing/Cuda/pbf_cuda_tests" --gtest_filter='CudaStepper.Outflows*'
sanitize memcheck "$build/Testing/Cuda/pbf_cuda_subdomain_tests" \
  --gtest_filter='CudaSubdomain.Outflows*'
# Liquids, surface tension and adhesion on ranks: seeds, migrants and three-field refreshes.
sanitize memcheck "$build/Testing/Cuda/pbf_cuda_subdomain_tests" \
  --gtest_filter='CudaSubdomain.LiquidsSurfaceTension*'
# Every shipped scene at small size under memcheck, racecheck and initcheck.
for scene in dam_break double_dam_break blob stream channel; do
  for tool in memcheck racecheck initcheck; do
    sanitize "$tool" "$run" --backend cuda --scene "$scene" --spacing 0.05 --steps 6 --report 3
  done
done

phase "soak: 10,000 steps at 1M particles on the GPU"
timeout "$(limit 150)" "$build/Solver/Tools/pbf_soak" --backend cuda --particles 1000000 \
  --steps 10000 --check 1000 >"$work/soak.log" 2>&1
soak_status=$?
cat "$work/soak.log"
record "soak 1M x 10000 steps: $(tail -n 1 "$work/soak.log") (exit $soak_status)"
fi

if ((quick)); then
  phase "ncu: skipped (quick run)"
else
phase "ncu"
# One step at 1M in the flow that the benchmark times: construction (evaluateAtRest: 13 kernels)
# and 60 warm-up steps (22 kernels each) are skipped.
timeout "$(limit 60)" ncu --clock-control none --metrics gpu__time_duration.sum --csv --page raw \
  --launch-skip 1333 --launch-count 22 \
  "$bench" --backend cuda --particles 1000000 --warmup 60 --steps 1 >"$out/ncu_times.csv" 2>&1 ||
  record "ncu times: FAILED or cut"
# The neighbour passes of the same step: 1 density pass at construction, 10 a step.
timeout "$(limit 100)" ncu --clock-control none --kernel-name-base demangled \
  -k 'regex:DensityStage|CorrectionStage|VorticityStage|ConfinementStage' --launch-skip 601 \
  --launch-count 10 --section SpeedOfLight --section Occupancy --section SchedulerStats \
  --section WarpStateStats --section MemoryWorkloadAnalysis --section LaunchStats \
  --metrics smsp__thread_inst_executed_per_inst_executed.ratio,smsp__inst_executed.sum \
  "$bench" --backend cuda --particles 1000000 --warmup 60 --steps 1 >"$out/ncu_sections.txt" 2>&1 ||
  record "ncu sections: FAILED or cut"
grep -E "Stage|Duration|Throughput|Achieved Occupancy|Issue Slots Busy|thread_inst_executed_per|Registers" \
  "$out/ncu_sections.txt" | head -80
fi

if [[ ${PBF_GPU_RESOLUTION:-0} != 0 ]]; then
  # The resolution runs (Documentation/Validation.md, "Resolution"): CSVs of every frame
  # into $out/resolution, the summary tables into the log. PBF_GPU_RESOLUTION=1: the 1.15M and
  # 9.2M dam breaks and the Martin & Moyce fronts; 2: the smoothing ratios, the CFL halving and
  # the CPU (OpenMP) dam breaks; 3: both; 5: the refined benchmark (pbf_bench --refined); 6: MARIN
  # at 2, 1 and 0.75 cm (pbf_marin; PBF_GPU_MARIN_SPACINGS other spacings); 7: the defaults alone
  # (the 1.15M and 9.2M dam breaks, Martin & Moyce at 40 and 80 across). Several at once:
  # PBF_GPU_RESOLUTION="2 6" (PBF_GPU_SKIP_OPENMP=1: level 2 without its OpenMP dam breaks).
  # PBF_GPU_SOLVER_ARGS (e.g. "--chebyshev 0.8") is added to every run of these phases, to
  # measure a solver option against the defaults in the same call.
  read -r -a solver_args <<<"${PBF_GPU_SOLVER_ARGS:-}"
  level() { [[ " $PBF_GPU_RESOLUTION " == *" $1 "* ]]; }
  res=$out/resolution
  mkdir -p "$res"
  bench=$build/Solver/Tools/pbf_bench
  mm=$build/Solver/Tools/pbf_martin_moyce
  experiment=$root/Testing/Validation/martin_moyce_1952_surge_front_n2.csv
  refine() { # refine NAME SECONDS ARGS...
    local name=$1 seconds=$2
    shift 2
    phase "resolution $name: $*"
    timeout "$(limit "$seconds")" "$bench" "$@" "${solver_args[@]}" --csv "$res" >"$res/$name.log" 2>&1
    local status=$?
    tail -n 10 "$res/$name.log"
    record "resolution $name: exit $status"
  }
  martin_moyce() { # martin_moyce ACROSS...: the fronts at these resolutions (and solver_args)
    local across
    for across in "$@"; do
      phase "martin-moyce $across across"
      timeout "$(limit 60)" "$mm" --backend cuda --across "$across" --experiment "$experiment" \
        "${solver_args[@]}" --front "$res/mm_$across.csv" >"$res/mm_$across.txt" 2>"$res/mm_$across.err"
      record "martin-moyce $across: $(grep -E 'rms_relative_error,|fitted' "$res/mm_$across.txt" | tr '\n' ' ')"
    done
  }
  if level 1 || level 3; then
    refine dam_break_1M 150 --backend cuda --refined 0.005 --until 2
    refine dam_break_9M 200 --backend cuda --refined 0.0025 --until 0.5
    martin_moyce 10 20 40 80
  fi
  if level 7; then
    # The defaults alone, to compare a solver option (PBF_GPU_SOLVER_ARGS) with them in one call:
    # the 1.15M and 9.2M dam breaks and Martin & Moyce at 40 and 80 across.
    refine dam_break_1M_defaults 100 --backend cuda --refined 0.005 --until 2 --modes defaults
    refine dam_break_9M_defaults 150 --backend cuda --refined 0.0025 --until 0.5 --modes defaults
    martin_moyce 40 80
  fi
  if level 5; then
    # The benchmark of the scene users run (Documentation/Performance.md): 144k and
    # 1.15M to 2 s, 9.2M to 0.5 s, fixed steps, automatic with 4 projections and the defaults.
    refine bench_refined 200 --backend cuda --refined 0.01,0.005 --until 2
    refine bench_refined_9M 200 --backend cuda --refined 0.0025 --until 0.5
  fi
  if level 6; then
    # MARIN (Kleefsman et al. 2005) to 6 s at 2, 1 and 0.75 cm: gauge heights against the records.
    marin_spacings=${PBF_GPU_MARIN_SPACINGS:-0.02,0.01,0.0075}
    phase "marin $marin_spacings to 6 s"
    timeout "$(limit 400)" "$build/Solver/Tools/pbf_marin" --backend cuda \
      --records "$root/Testing/Validation" --spacings "$marin_spacings" --until 6 "${solver_args[@]}" \
      --csv "$res/marin.csv" >"$res/marin.txt" 2>&1
    cat "$res/marin.txt"
    record "marin: $(tail -n +2 "$res/marin.txt" | tr '\n' ' ')"
  fi
  if level 4; then
    refine dam_break_1M_defaults 60 --backend cuda --refined 0.005 --until 2 --modes defaults
    # The CPU's finest case: OpenMP on this machine's cores.
    refine dam_break_openmp_fine 420 --backend openmp --refined 0.01 --until 2 --modes defaults
  fi
  if level 2 || level 3; then
    for ratio in 1.5 2 2.5 3; do
      refine "tank_ratio_$ratio" 40 --backend cuda --scene "$root/Testing/Validation/hydrostatic_tank.json" \
        --refined 0.02 --smoothing-ratio "$ratio" --until 0.5 --modes defaults
      refine "dam_break_ratio_$ratio" 40 --backend cuda --refined 0.02 --smoothing-ratio "$ratio" \
        --until 2 --modes defaults
      mv "$res/dam_break_0.02_defaults_CUDA.csv" "$res/dam_break_0.02_ratio_$ratio.csv" 2>/dev/null
      mv "$res/hydrostatic_tank_0.02_defaults_CUDA.csv" "$res/tank_0.02_ratio_$ratio.csv" 2>/dev/null
    done
    # Into a folder of their own: the CSVs are named by scene, spacing, mode and backend only.
    mkdir -p "$res/cfl0.2"
    res_main=$res
    res=$res/cfl0.2
    refine dam_break_cfl_0.2 60 --backend cuda --refined 0.01,0.005 --until 2 --modes defaults --cfl 0.2
    res=$res_main
    for f in "$res"/cfl0.2/dam_break_*_defaults_CUDA.csv; do
      [[ -f $f ]] && mv "$f" "$res/$(basename "${f%.csv}")_cfl0.2.csv"
    done
    refine dam_break_cuda_coarse 60 --backend cuda --refined 0.04,0.02,0.01 --until 2 --modes defaults
    for across in 40 80; do
      phase "martin-moyce $across across, CFL 0.2"
      timeout "$(limit 60)" "$mm" --backend cuda --across "$across" --experiment "$experiment" \
        --dt-factor 0.5 "${solver_args[@]}" --front "$res/mm_${across}_cfl0.2.csv" \
        >"$res/mm_${across}_cfl0.2.txt" 2>&1
      record "martin-moyce $across, CFL 0.2: $(grep -E 'rms_relative_error,' "$res/mm_${across}_cfl0.2.txt")"
    done
    if [[ ${PBF_GPU_SKIP_OPENMP:-0} != 1 ]]; then
      refine dam_break_openmp 200 --backend openmp --refined 0.04,0.02,0.01 --until 2 --modes defaults
    fi
  fi
  # The device tool brings back a limited number of files: one archive of them all.
  (cd "$out" && tar czf resolution.tar.gz resolution && rm -rf resolution)
fi

if [[ ${PBF_GPU_PAIR_PROBE:-0} == 1 ]]; then
  # The neighbour passes' structures, measured apart from the solver (Documentation/Performance.md,
  # "Why the kernels are built this way"): a density-like pass as an ideal
  # gather, with each pair once and scattered, and with the candidates from a list or row masks.
  phase "pair_once_probe"
  if nvcc -O3 -arch=sm_90 -o "$work/pair_once_probe" "$root/Utilities/gpu/pair_once_probe.cu" \
      >"$work/probe_build.log" 2>&1; then
    for edge in 100 160; do
      timeout "$(limit 60)" "$work/pair_once_probe" "$edge" 2>&1 | tee "$work/probe_$edge.log"
      record "pair_once_probe $edge^3: $(grep -h 'ms' "$work/probe_$edge.log" | tr '\n' ' ')"
    done
  else
    tail -n 20 "$work/probe_build.log"
    record "pair_once_probe: build FAILED"
  fi
fi

phase "summary"
python3 - "$work" "$out/bench.json" <<'PY'
import glob, json, os, sys
work, target = sys.argv[1], sys.argv[2]
runs = []
for path in sorted(glob.glob(os.path.join(work, "*.json"))):
    try:
        data = json.load(open(path))
    except Exception as error:
        print("unreadable", path, error)
        continue
    for r in data["runs"]:
        r["label"] = data["label"]
        runs.append(r)
json.dump({"runs": runs}, open(target, "w"), indent=1)
PY
# $OUT keeps five files: run.log, bench.json, ncu_times.csv, ncu_sections.txt, logs.tar.gz.
(cd "$work" && tar czf "$out/logs.tar.gz" ./*.log ./*.json ./*.sass.gz) 2>/dev/null

echo
echo "== [$((SECONDS - t0)) s] results"
for line in "${results[@]}"; do echo "  $line"; done
python3 - "$out/bench.json" <<'PY' || echo "summary: no CUDA results to tabulate"
import json, sys
runs = json.load(open(sys.argv[1]))["runs"]
def pick(label):
    return {r["particles"]: r for r in runs if r["label"] == label}
single, double, walk, serial = pick("cuda_single"), pick("cuda_double"), pick("cuda_walk"), pick("serial")
extra = {r["particles"]: r for r in runs if r["label"] in ("cuda_10M", "cuda_100M")}
serial.update({r["particles"]: r for r in runs if r["label"] == "serial_1M"})
single.update(extra)
# Serial ms per particle-step from its largest measured run; extrapolated linearly beyond.
per = None
if serial:
    n = max(serial)
    per = serial[n]["median_ms"] / n
print("%10s %10s %9s %10s %9s %9s %10s %9s" % ("particles", "f32 ms", "steps/s", "f64 ms", "B/part",
      "builds", "serial ms", "speedup"))
for n in sorted(single):
    r = single[n]
    d = min(double, key=lambda m: abs(m - n)) if double else None
    dms = double[d]["median_ms"] if d and abs(d - n) < 0.1 * n else float("nan")
    s = serial[n]["median_ms"] if n in serial else (per * n if per else float("nan"))
    mark = "" if n in serial else "*"
    print("%10d %10.3f %9.1f %10.3f %9.0f %9.2f %9.1f%s %9.0f" % (n, r["median_ms"],
          r["steps_per_second"], dms, r["device_bytes_per_particle"], r["mask_builds_per_step"], s,
          mark, s / r["median_ms"]))
print("* serial extrapolated linearly from its largest measured count")
for n in sorted(walk):
    m = min(single, key=lambda k: abs(k - n))
    print("walk %9d: %8.3f ms   masks: %8.3f ms" % (n, walk[n]["median_ms"], single[m]["median_ms"]))
for r in runs:
    if r["label"].startswith(("cuda_skin", "cuda_nowalls")) or r["label"] == "cuda_nographs":
        print("%-14s %9d: %8.3f ms  builds/step %.2f" % (r["label"], r["particles"], r["median_ms"],
              r["mask_builds_per_step"]))
PY
